#!/usr/bin/env bash
# Fuzzes every built harness of tests/fuzz for SECONDS each (default 30).
# Builds nothing: configure and build the harnesses first (README "Fuzzing"):
#   CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DAUVNAV_FUZZ=ON
#   cmake --build build-fuzz -j2 --target auvnav_fuzz
#   tests/fuzz/run_all.sh [SECONDS] [BUILD_DIR]      (BUILD_DIR default: build-fuzz)
# .ci/sanitize runs it for 30 s per harness in its sanitized build (FUZZ_SEED=1).
# Each harness starts from a fresh temporary corpus, a copy of its committed
# seeds and regressions, so the repository is never written to. Stops at the
# first harness that finds something (crash, sanitizer report, leak,
# timeout, out-of-memory): the input is left as crash-*/leak-*/timeout-*/oom-*
# in ARTIFACTS (default: a temporary folder, printed, and removed again when
# every harness ran without a finding), to be minimised and committed under
# tests/fuzz/regressions/<name>/ with the fix.
set -euo pipefail
seconds="${1:-30}"
here="$(cd "$(dirname "$0")" && pwd)"
build="${2:-$here/../../build-fuzz}"
own_artifacts=0
if [ -z "${ARTIFACTS:-}" ]; then
	artifacts="$(mktemp -d /tmp/auvnav-fuzz-artifacts.XXXXXX)"
	own_artifacts=1  # a folder of our own: removed again when nothing was found
else
	artifacts="$ARTIFACTS"
fi
mkdir -p "$artifacts"
# Largest input per harness: room for a few records, small enough to keep
# executions fast (rawlogs of several objects, YAML files of a few KB).
declare -A max_len=([rawlog]=16384 [config]=8192 [csv_import]=4096 [plugin_prepare]=2048 [stretch]=4096)
# Leak detection off where MRPT's YAML reader (libfyaml) leaks on parse
# errors: libFuzzer then runs a full LeakSanitizer pass after nearly every
# input (17 instead of 400 executions/s). The replay tests (ctest -L fuzz)
# still check every committed input for leaks, with the suppressions of
# harness_runtime.cpp.
declare -A extra=([config]=-detect_leaks=0 [csv_import]=-detect_leaks=0)
# FUZZ_SEED: libFuzzer's random seed (CI fixes it; default: a new one per run).
seed_arg=""
[ -n "${FUZZ_SEED:-}" ] && seed_arg="-seed=$FUZZ_SEED"
status=0
for bin in "$build"/bin/fuzz_*; do
	[ -x "$bin" ] || continue
	name="${bin##*/fuzz_}"
	corpus="$(mktemp -d /tmp/auvnav-fuzz-corpus-"$name".XXXXXX)"
	cp -r "$here/corpus/$name/." "$corpus/" 2>/dev/null || true
	cp -r "$here/regressions/$name/." "$corpus/" 2>/dev/null || true
	echo "== fuzz_$name: ${seconds}s, corpus $corpus"
	if ! "$bin" -max_total_time="$seconds" -max_len="${max_len[$name]:-1024}" -rss_limit_mb=2048 -timeout=10 \
		-print_final_stats=1 $seed_arg -artifact_prefix="$artifacts/fuzz_$name-" ${extra[$name]:-} "$corpus" > "$artifacts/fuzz_$name.log" 2>&1; then
		tail -n 60 "$artifacts/fuzz_$name.log"
		echo "fuzz_$name FOUND SOMETHING: the input is under $artifacts (log: fuzz_$name.log)" >&2
		status=1
		rm -rf "$corpus"
		break
	fi
	# The final stats: executions, coverage (cov: edges, ft: features), corpus size.
	grep -E "^(#[0-9]+\s+DONE|stat::number_of_executed_units|stat::peak_rss_mb)" "$artifacts/fuzz_$name.log" || true
	rm -rf "$corpus"
done
if [ "$status" -eq 0 ]; then
	echo "all harnesses ran ${seconds}s without a finding"
	[ "$own_artifacts" -eq 1 ] && rm -rf "$artifacts"
fi
exit "$status"
