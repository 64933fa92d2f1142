#!/usr/bin/env bash
# auvnav-experiment with `smooth: true` (tests/experiment/two_seeds_smoothed.yaml):
#   smoothed_test.sh EXE EXPERIMENT WORKDIR
# Both configurations get a smoothed row at mid-denial whose error is below
# the filter's (measured: 0.74 and 0.65 of it), with the smoothed error
# inside its 2σ in both seeds, and --jobs 2 writes the tables of --jobs 1.
set -euo pipefail
exe=$1 experiment=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }
"$exe" "$experiment" --jobs 1 --out "$work/j1" > "$work/j1.log" 2>&1 || { cat "$work/j1.log"; fail "--jobs 1"; }
"$exe" "$experiment" --jobs 2 --out "$work/j2" > "$work/j2.log" 2>&1 || { cat "$work/j2.log"; fail "--jobs 2"; }
cmp "$work/j1/denial_table.md" "$work/j2/denial_table.md" || fail "--jobs 2 table differs from --jobs 1's"
table="$work/j1/denial_table.md"
grep -q "^Smoothed (" "$table" || { cat "$table"; fail "no smoothed table"; }
rows=0
while IFS='|' read -r _ name filtered smoothed ratio worst two_sigma inside _; do
	rows=$((rows + 1))
	awk -v r="$ratio" 'BEGIN { exit !(r + 0 > 0 && r + 0 < 0.8) }' || fail "$name: smoothed/filtered $ratio, expected < 0.8"
	[ "$(echo "$inside" | tr -d ' ')" = "2/2" ] || fail "$name: smoothed inside 2 sigma $inside, expected 2/2"
	echo "$name: filtered$filtered, smoothed$smoothed, ratio$ratio, inside$inside"
done < <(sed -n '/^Smoothed (/,$p' "$table" | grep '^| Inertial')
[ "$rows" -eq 2 ] || fail "expected 2 smoothed rows, got $rows"
