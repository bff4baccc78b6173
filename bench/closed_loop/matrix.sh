#!/usr/bin/env bash
# The standard closed-loop evaluation matrix (issue 26), with the shipped defaults at VGA:
# every shipped world x {none, light x0.6, light x1.4, furniture, person, crowd, drops, latency},
# 10 starts each, seed 1; plus 20 generated worlds (`pepper_app world generate`, seeds 1 to 20,
# kinds room / corridor / building in turn: seed % 3 = 1, 2, 0) x {none, light x0.7}, 5 starts
# each. The generated worlds are written by this script into DIR/worlds/ before the runs (the
# generator is deterministic; a file already there is kept, so a resumed matrix evaluates the
# same files even if the generator changed meanwhile). One `pepper_app evaluate` process per
# configuration, two side by side (both cores); each configuration keeps its own JSON, so a
# matrix can be run in shards across sessions and combined (bench/closed_loop/combine.py). A
# configuration whose JSON exists is skipped, so the same command resumes an interrupted matrix.
# Each configuration's plots and report (evaluate --plots) go to DIR/NAME/; combine.py --html
# links them from one index page.
#
# Usage: bench/closed_loop/matrix.sh [--out DIR] [--app BIN] [--size WxH] [--starts N]
#                                    [--gen-starts N] [--gen-seeds N] [--gen-first-seed S]
#                                    [--jobs N] [--shard I/N] [--only REGEX] [--list]
#                                    [--mode forward|ceiling] [--set KEY=VALUE]...
#   --gen-starts N  starts per generated world (5); --gen-seeds N: seeds 1..N (20; 0: none)
#   --gen-first-seed S  the generated worlds' seeds start at S instead of 1 (S..S+N-1): fresh
#                 worlds nothing was tuned on, e.g. --gen-first-seed 101
#   --shard I/N   run only configurations I, I+N, I+2N, ... (1-based) of the list
#   --only REGEX  run only configurations whose name matches (e.g. 'robotics_room', 'light',
#                 '^gen_' for the generated worlds only)
#   --list        print the configuration names and exit
#   --set K=V     passed to every `pepper_app evaluate` (repeatable): an ablation runs the matrix
#                 with one navigator rule off, e.g. --set navigator.switching.min_next_scale_ratio=0
#   --mode M      what the robot navigates by (evaluate --mode; forward by default): ceiling runs
#                 the same configurations looking at the ceiling (issue 24)
# Example (two sessions, each half of the matrix, then one table):
#   bench/closed_loop/matrix.sh --out /work/eval/matrix --shard 1/2
#   bench/closed_loop/matrix.sh --out /work/eval/matrix --shard 2/2
#   bench/closed_loop/combine.py /work/eval/matrix/*.json --html /work/eval/matrix/index.html
# Cost: about 1 to 3 minutes per run at VGA with two processes on a quiet 2-core machine
# (7 x 4 x 10 = 280 shipped runs + 20 x 2 x 5 = 200 generated runs: several sessions).
set -euo pipefail
cd "$(dirname "$0")/../.."
OUT=bench/closed_loop/out/matrix
APP=build/pepper_app/pepper_app
SIZE=640x480
STARTS=10
GEN_STARTS=5
GEN_SEEDS=20
GEN_FIRST_SEED=1
JOBS=2
SHARD=1/1
ONLY=.
LIST=0
SETS=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) OUT=$2; shift 2 ;;
    --app) APP=$2; shift 2 ;;
    --size) SIZE=$2; shift 2 ;;
    --starts) STARTS=$2; shift 2 ;;
    --gen-starts) GEN_STARTS=$2; shift 2 ;;
    --gen-seeds) GEN_SEEDS=$2; shift 2 ;;
    --gen-first-seed) GEN_FIRST_SEED=$2; shift 2 ;;
    --jobs) JOBS=$2; shift 2 ;;
    --shard) SHARD=$2; shift 2 ;;
    --only) ONLY=$2; shift 2 ;;
    --list) LIST=1; shift ;;
    --set) SETS+=(--set "$2"); shift 2 ;;
    --mode) SETS+=(--mode "$2"); shift 2 ;;
    -h|--help) sed -n '2,35p' "$0"; exit 0 ;;
    *) echo "matrix.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
WORLDS=(robotics_room room_corridor_room white_corridor window_corridor)
# name|evaluate arguments
CONFIGS=()
for w in "${WORLDS[@]}"; do
  S="--starts $STARTS --world worlds/$w.yaml"
  CONFIGS+=("${w}_none|$S --disturbance none")
  CONFIGS+=("${w}_light0.6|$S --disturbance light --light-factor 0.6")
  CONFIGS+=("${w}_light1.4|$S --disturbance light --light-factor 1.4")
  for d in furniture person crowd drops latency; do
    CONFIGS+=("${w}_$d|$S --disturbance $d")
  done
done
GEN_KINDS=(building room corridor)  # by seed % 3
gen_world() { echo "gen_${GEN_KINDS[$(( $1 % 3 ))]}_$1"; }
for (( seed = GEN_FIRST_SEED; seed < GEN_FIRST_SEED + GEN_SEEDS; ++seed )); do
  g=$(gen_world "$seed")
  S="--starts $GEN_STARTS --world $OUT/worlds/$g.yaml"
  CONFIGS+=("${g}_none|$S --disturbance none")
  CONFIGS+=("${g}_light0.7|$S --disturbance light --light-factor 0.7")
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
mkdir -p "$OUT/worlds"
# The generated worlds the selected configurations need, written before any run starts.
for c in "${SELECTED[@]}"; do
  name=${c%%|*}
  [[ $name == gen_* ]] || continue
  g=${name%_*}
  seed=${g##*_}
  kind=${g#gen_}
  kind=${kind%_*}
  if [[ ! -s $OUT/worlds/$g.yaml ]]; then
    # Written under a name of this process's own and renamed: two shards side by side need the
    # same worlds (a world's none and light configurations fall in different shards), and one
    # must never read the file the other is writing.
    tmp="$OUT/worlds/.$g.$$.yaml"
    "$APP" world generate --seed "$seed" --kind "$kind" --out "$tmp" \
        --textures worlds/textures > /dev/null
    mv -f "$tmp" "$OUT/worlds/$g.yaml"
  fi
done
run_one() {
  local name=${1%%|*} args=${1#*|}
  if [[ -s $OUT/$name.json ]]; then echo "skip $name (done)"; return 0; fi
  echo "$(date +%T) start $name"
  # shellcheck disable=SC2086
  "$APP" evaluate $args $EVAL_SETS --seed 1 --size "$SIZE" --json "$OUT/$name.json.tmp" \
      --plots "$OUT/$name" > "$OUT/$name.txt" 2> "$OUT/$name.log" || true
  if [[ -s $OUT/$name.json.tmp ]]; then mv "$OUT/$name.json.tmp" "$OUT/$name.json"; fi
  echo "$(date +%T) done  $name"
}
export -f run_one
# Settings as one word-split string (keys and values have no spaces): xargs's children cannot
# inherit a bash array.
EVAL_SETS="${SETS[*]}"
export OUT APP SIZE EVAL_SETS
# Stopping the script (Ctrl-C, kill) stops its runs too: xargs and the evaluate processes under it
# would otherwise go on without it. A stopped run leaves no JSON (it writes *.json.tmp), so the
# same command resumes it.
kill_tree() {
  local child
  for child in $(pgrep -P "$1"); do kill_tree "$child"; done
  kill "$1" 2> /dev/null || true
}
XARGS=
trap '[[ -n $XARGS ]] && kill_tree "$XARGS"; echo "matrix.sh: stopped; the same command resumes" >&2
      exit 143' INT TERM HUP
printf '%s\n' "${SELECTED[@]}" | xargs -d '\n' -P "$JOBS" -I{} bash -c 'run_one "$@"' _ {} &
XARGS=$!
wait "$XARGS"
trap - INT TERM HUP
echo "tables: bench/closed_loop/combine.py $OUT/*.json --html $OUT/index.html"
