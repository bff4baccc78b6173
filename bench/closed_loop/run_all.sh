#!/usr/bin/env bash
# Full closed-loop evaluation (docs/evaluation.md): the four shipped worlds, 10 perturbed starts
# each, combined features, then the light and person disturbances and the feature comparison.
# Usage: bench/closed_loop/run_all.sh [BUILD_DIR] [SIZE] [STARTS] [OUT_DIR]
# Defaults: build, 640x480, 10, bench/closed_loop/out. Expect hours at VGA on one core
# (~1500-2500 frames per run); 320x240 is about 4x faster.
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD=${1:-build}
SIZE=${2:-640x480}
STARTS=${3:-10}
OUT=${4:-bench/closed_loop/out}
APP="$BUILD/pepper_app/pepper_app"
mkdir -p "$OUT"
WORLDS=(worlds/robotics_room.yaml worlds/room_corridor_room.yaml worlds/white_corridor.yaml
        worlds/window_corridor.yaml)

# 1. Baseline + light change + walking person, combined features, every world.
for w in "${WORLDS[@]}"; do
  name=$(basename "$w" .yaml)
  "$APP" evaluate --world "$w" --starts "$STARTS" --size "$SIZE" --seed 1 \
      --disturbance none light person \
      --json "$OUT/$name.json" --plots "$OUT/$name" | tee "$OUT/$name.txt" || true
done

# 2. The paper's comparison: lines only, points only, combined (no disturbance).
for w in "${WORLDS[@]}"; do
  name=$(basename "$w" .yaml)
  "$APP" evaluate --world "$w" --starts "$STARTS" --size "$SIZE" --seed 1 --compare-features \
      --json "$OUT/${name}_compare.json" --plots "$OUT/${name}_compare" \
      | tee "$OUT/${name}_compare.txt" || true
done

# 3. Robot-side disturbances on one world.
"$APP" evaluate --world worlds/window_corridor.yaml --starts "$STARTS" --size "$SIZE" --seed 1 \
    --disturbance drops latency furniture \
    --json "$OUT/window_corridor_robot.json" --plots "$OUT/window_corridor_robot" \
    | tee "$OUT/window_corridor_robot.txt" || true
