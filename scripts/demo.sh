#!/usr/bin/env bash
# The main job for a newcomer: set up, build, then teach a tour on the simulated Pepper, replay it
# from a perturbed start and write an HTML report (its path is printed at the end).
#   scripts/demo.sh                       # robotics_room's whole loop (about a minute), demo_out/
#   scripts/demo.sh --quick               # its first straight only (a few seconds)
#   scripts/demo.sh --ui                  # same, watch it live in a browser (URL printed)
#   scripts/demo.sh --world worlds/white_corridor.yaml --out /tmp/demo
# Any option is passed to `pepper_app demo` (see `pepper_app demo --help`).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
BUILD_DIR=${BUILD_DIR:-build}
"$BUILD_DIR"/pepper_app/pepper_app version
exec "$BUILD_DIR"/pepper_app/pepper_app demo "$@"
