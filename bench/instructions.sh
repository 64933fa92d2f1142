#!/usr/bin/env bash
# Instructions per IMU tick of auvnav-run, counted by callgrind (noise-free,
# comparable between machines, unlike wall time), on a fixed input:
# bench/cut_120s.rawlog, the first 120 s of the sample mission with every
# sensor (IMU + accelerometer, DVL, pressure, ADCP, model aiding, GPS), cut
# with `rawlog-edit --cut --to-time 1492693320` and committed so that the
# figure stays comparable when the sample is regenerated.
#
#   bench/instructions.sh [--build DIR] [--config FILE] [--rawlog FILE]
#                         [--work DIR] [--no-sensors]
#
# Prints one table: the whole program, then stages (inclusive instructions
# of one function each, from one callgrind run):
#   prediction      ManifoldUkf::predict (the IMU tick's unscented prediction)
#   sensor updates  Navigator::dispatch (every sensor's prepare + update)
#   outputs         RunOutputs::onState (states.csv, trajectory.tum rows)
#   rawlog reading  RawlogReader::next
#   process start-up  everything outside main() (dynamic loading, static
#                   constructors); and the whole program less that
# then, unless --no-sensors, one callgrind run per sensor with collection on
# only inside that sensor's updates (AUVNAV_CALLGRIND_SENSOR, apps/run/main.cpp).
# Each figure is divided by the run's IMU predictions (summary.json).
# Needs valgrind (Debian: valgrind); ~1 min per callgrind run.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$here")"
build="$repo/build"
config="$repo/config/flatfish.yaml"
rawlog="$here/cut_120s.rawlog"
work=""
per_sensor=1
while (($#)); do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --config) config="$2"; shift 2 ;;
    --rawlog) rawlog="$2"; shift 2 ;;
    --work) work="$2"; shift 2 ;;
    --no-sensors) per_sensor=0; shift ;;
    -h|--help) sed -n '2,22p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "instructions.sh: unknown argument '$1' (see --help)" >&2; exit 1 ;;
  esac
done
run="$build/bin/auvnav-run"
[[ -x "$run" ]] || { echo "instructions.sh: no auvnav-run at $run (build first, or --build DIR)" >&2; exit 1; }
[[ -f "$rawlog" ]] || { echo "instructions.sh: no rawlog $rawlog" >&2; exit 1; }
command -v valgrind >/dev/null || { echo "instructions.sh: valgrind is not installed (apt-get install valgrind)" >&2; exit 1; }
if [[ -z "$work" ]]; then
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
fi
mkdir -p "$work"

# callgrind OUT_FILE RUN_DIR [valgrind options...]: auvnav-run under callgrind.
callgrind() {
  local out="$1" dir="$2"
  shift 2
  rm -rf "$dir"
  if ! valgrind --tool=callgrind --callgrind-out-file="$out" "$@" \
      "$run" --config "$config" --out "$dir" --quiet "$rawlog" >"$out.log" 2>&1; then
    echo "instructions.sh: auvnav-run failed under callgrind (see $out.log):" >&2
    tail -5 "$out.log" >&2
    exit 2
  fi
}
# Total instructions of a callgrind output file.
# (The awk scripts read to the end: an early exit would fail the pipe under pipefail.)
total() { callgrind_annotate "$1" 2>/dev/null | awk '/PROGRAM TOTALS/ && !n { gsub(",", "", $1); n = $1 } END { printf "%.0f\n", n }'; }
# Inclusive instructions of the first function whose name starts with $2.
inclusive() {
  callgrind_annotate --inclusive=yes --threshold=100 "$1" 2>/dev/null |
    awk -v fn="$2" '!found && index($0, ":" fn) { gsub(",", "", $1); n = $1; found = 1 } END { printf "%.0f\n", n }'
}

callgrind "$work/all.cg" "$work/all"
ticks=$(sed -n 's/^ *"predictions": *\([0-9]*\).*/\1/p' "$work/all/summary.json" | head -1)
[[ -n "$ticks" && "$ticks" -gt 0 ]] || { echo "instructions.sh: no IMU predictions in $work/all/summary.json" >&2; exit 2; }
all=$(total "$work/all.cg")

row() { awk -v n="$2" -v t="$ticks" -v all="$all" -v name="$1" \
  'BEGIN { printf "%-28s %16.0f %12.1f %7.1f %%\n", name, n, n / t / 1000, 100 * n / all }'; }
echo "auvnav-run on $(basename "$rawlog") ($(git -C "$repo" rev-parse --short HEAD 2>/dev/null || echo '?')): $ticks IMU ticks"
printf "%-28s %16s %12s %9s\n" "stage" "instructions" "k per tick" "of all"
row "whole program" "$all"
row "prediction" "$(inclusive "$work/all.cg" "auvnav::ManifoldUkf::predict(Eigen")"
row "sensor updates (all)" "$(inclusive "$work/all.cg" "auvnav::Navigator::dispatch(")"
row "outputs" "$(inclusive "$work/all.cg" "auvnav::run::RunOutputs::onState(")"
row "rawlog reading" "$(inclusive "$work/all.cg" "auvnav::io::RawlogReader::next(")"
# Loading and relocating the ~170 shared libraries MRPT's observation library
# pulls in (OpenCV's codecs bring GDAL, GDCM, poppler ...) and their static
# constructors: a fixed cost per process, not per tick (it is spread over the
# cut's ticks here; over a 1 h log it is ~30 times smaller per tick).
in_main=$(inclusive "$work/all.cg" "main [")
row "process start-up (outside main)" "$((all - in_main))"
row "whole program less start-up" "$in_main"

if ((per_sensor)); then
  # Sensor labels (not the IMU prediction's "(prediction)" entry) from summary.json.
  awk '/"label":/ { gsub(/[",]/, "", $2); l = $2 } /"plugin":/ { gsub(/[",]/, "", $2); if ($2 != "(prediction)") print l, $2 }' \
    "$work/all/summary.json" >"$work/sensors.txt"
  while read -r label plugin; do
    AUVNAV_CALLGRIND_SENSOR="$label" callgrind "$work/$label.cg" "$work/$label" --collect-atstart=no
    row "  $label ($plugin)" "$(total "$work/$label.cg")"
  done <"$work/sensors.txt"
fi
