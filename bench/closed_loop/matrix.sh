#!/usr/bin/env bash
# The standard closed-loop evaluation matrix (issue 26), with the shipped defaults at VGA:
# every shipped world x {none, light x0.6, light x1.4, furniture, person, drops, latency},
# 10 starts each, seed 1. One `pepper_app evaluate` process per configuration, two side by side
# (both cores); each configuration keeps its own JSON, so a matrix can be run in shards across
# sessions and combined (bench/closed_loop/combine.py). A configuration whose JSON exists is
# skipped, so the same command resumes an interrupted matrix.
#
# Usage: bench/closed_loop/matrix.sh [--out DIR] [--app BIN] [--size WxH] [--starts N]
#                                    [--jobs N] [--shard I/N] [--only REGEX] [--list]
#   --shard I/N   run only configurations I, I+N, I+2N, ... (1-based) of the list
#   --only REGEX  run only configurations whose name matches (e.g. 'robotics_room' or 'light')
#   --list        print the configuration names and exit
# Example (two sessions, each half of the matrix, then one table):
#   bench/closed_loop/matrix.sh --out /work/eval/matrix --shard 1/2
#   bench/closed_loop/matrix.sh --out /work/eval/matrix --shard 2/2
#   bench/closed_loop/combine.py /work/eval/matrix/*.json
# Cost: about 1 to 3 minutes per run at VGA with two processes on a quiet 2-core machine
# (7 x 4 x 10 = 280 runs: several sessions).
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=bench/closed_loop/out/matrix
APP=build/pepper_app/pepper_app
SIZE=640x480
STARTS=10
JOBS=2
SHARD=1/1
ONLY=.
LIST=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) OUT=$2; shift 2 ;;
    --app) APP=$2; shift 2 ;;
    --size) SIZE=$2; shift 2 ;;
    --starts) STARTS=$2; shift 2 ;;
    --jobs) JOBS=$2; shift 2 ;;
    --shard) SHARD=$2; shift 2 ;;
    --only) ONLY=$2; shift 2 ;;
    --list) LIST=1; shift ;;
    -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
    *) echo "matrix.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
WORLDS=(robotics_room room_corridor_room white_corridor window_corridor)
# name|evaluate arguments
CONFIGS=()
for w in "${WORLDS[@]}"; do
  CONFIGS+=("${w}_none|--world worlds/$w.yaml --disturbance none")
  CONFIGS+=("${w}_light0.6|--world worlds/$w.yaml --disturbance light --light-factor 0.6")
  CONFIGS+=("${w}_light1.4|--world worlds/$w.yaml --disturbance light --light-factor 1.4")
  for d in furniture person drops latency; do
    CONFIGS+=("${w}_$d|--world worlds/$w.yaml --disturbance $d")
  done
done
I=${SHARD%/*}
N=${SHARD#*/}
SELECTED=()
for k in "${!CONFIGS[@]}"; do
  name=${CONFIGS[$k]%%|*}
  if (( k % N == I - 1 )) && [[ $name =~ $ONLY ]]; then SELECTED+=("${CONFIGS[$k]}"); fi
done
if (( LIST )); then
  for c in "${SELECTED[@]}"; do echo "${c%%|*}"; done
  exit 0
fi
[[ -x $APP ]] || { echo "matrix.sh: $APP not found: build first (scripts/build.sh)" >&2; exit 2; }
mkdir -p "$OUT"
run_one() {
  local name=${1%%|*} args=${1#*|}
  if [[ -s $OUT/$name.json ]]; then echo "skip $name (done)"; return 0; fi
  echo "$(date +%T) start $name"
  # shellcheck disable=SC2086
  "$APP" evaluate $args --starts "$STARTS" --seed 1 --size "$SIZE" --json "$OUT/$name.json.tmp" \
      > "$OUT/$name.txt" 2> "$OUT/$name.log" || true
  if [[ -s $OUT/$name.json.tmp ]]; then mv "$OUT/$name.json.tmp" "$OUT/$name.json"; fi
  echo "$(date +%T) done  $name"
}
export -f run_one
export OUT APP STARTS SIZE
printf '%s\n' "${SELECTED[@]}" | xargs -d '\n' -P "$JOBS" -I{} bash -c 'run_one "$@"' _ {}
echo "tables: bench/closed_loop/combine.py $OUT/*.json"
