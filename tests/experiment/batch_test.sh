#!/usr/bin/env bash
# auvnav-experiment's batches (issue 16 item 4) on tests/experiment/two_seeds.yaml:
#   batch_test.sh EXE EXPERIMENT WORKDIR jobs      --jobs 2 writes the tables of --jobs 1, byte for byte
#   batch_test.sh EXE EXPERIMENT WORKDIR parallel PARALLEL
#                                                  --emit-jobs, GNU parallel, --collect: the same tables
#   batch_test.sh EXE EXPERIMENT WORKDIR failure   a failed run is named, the others' results kept
set -euo pipefail
exe=$1 experiment=$2 work=$3 mode=$4 gnu_parallel=${5:-parallel}
rm -rf "$work"
mkdir -p "$work"

fail() { echo "FAIL: $*" >&2; exit 1; }

# The reference: every run in this process.
reference() {
	"$exe" "$experiment" --jobs 1 --out "$work/j1" > "$work/j1.log" 2>&1 || { cat "$work/j1.log"; fail "--jobs 1"; }
}
same_tables() {  # DIR: its tables equal the --jobs 1 ones
	for f in denial_table.md runs.csv; do
		cmp "$work/j1/$f" "$1/$f" || fail "$1/$f differs from --jobs 1's"
	done
	echo "$1: denial_table.md and runs.csv identical to --jobs 1's"
}

case $mode in
jobs)
	reference
	"$exe" "$experiment" --jobs 2 --out "$work/j2" > "$work/j2.log" 2>&1 || { cat "$work/j2.log"; fail "--jobs 2"; }
	same_tables "$work/j2"
	;;
parallel)
	reference
	"$exe" "$experiment" --emit-jobs "$work/jobs.txt" --out "$work/p" > "$work/emit.log" 2>&1 ||
		{ cat "$work/emit.log"; fail "--emit-jobs"; }
	[ "$(wc -l < "$work/jobs.txt")" -eq 2 ] || fail "jobs.txt: expected 2 lines (one per seed)"
	[ ! -e "$work/p/denial_table.md" ] || fail "--emit-jobs ran something"
	# Each line is self-contained: run them from another directory.
	(cd / && "$gnu_parallel" --will-cite --halt now,fail=1 -j2 < "$work/jobs.txt") > "$work/parallel.log" 2>&1 ||
		{ cat "$work/parallel.log"; fail "GNU parallel"; }
	"$exe" "$experiment" --collect "$work/p" > "$work/collect.log" 2>&1 || { cat "$work/collect.log"; fail "--collect"; }
	same_tables "$work/p"
	;;
failure)
	# seed 4's simulation cannot create its directory: a plain file is in the way.
	mkdir -p "$work/f"
	touch "$work/f/seed_4"
	rc=0
	"$exe" "$experiment" --jobs 2 --out "$work/f" > "$work/f.log" 2>&1 || rc=$?
	cat "$work/f.log"
	[ "$rc" -eq 2 ] || fail "exit code $rc, expected 2"
	grep -q "error: the run of seed 4 failed" "$work/f.log" || fail "the failed run is not named"
	grep -q "1 of 2 runs failed (seed 4)" "$work/f.log" || fail "no summary of the failed runs"
	[ -f "$work/f/runs/seed_3.result" ] || fail "seed 3's result was not kept"
	[ ! -e "$work/f/denial_table.md" ] || fail "a table from an incomplete set of runs"
	rc=0
	"$exe" "$experiment" --collect "$work/f" > "$work/collect.log" 2>&1 || rc=$?
	cat "$work/collect.log"
	[ "$rc" -eq 2 ] && grep -q "no result for seed(s) 4" "$work/collect.log" || fail "--collect does not name the missing seed"
	# Rerun the failed seed alone, then collect.
	rm "$work/f/seed_4"
	"$exe" "$experiment" --seed 4 --out "$work/f" > "$work/rerun.log" 2>&1 || { cat "$work/rerun.log"; fail "--seed 4"; }
	"$exe" "$experiment" --collect "$work/f" > "$work/collect2.log" 2>&1 || { cat "$work/collect2.log"; fail "--collect after the rerun"; }
	[ -f "$work/f/denial_table.md" ] || fail "no table after the rerun"
	echo "failed run named, the other kept; rerun + --collect gives the table"
	;;
*) fail "unknown mode $mode" ;;
esac
