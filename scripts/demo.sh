#!/usr/bin/env bash
# The main job for a newcomer: set up, build, then run the demo on the mock robot.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
BUILD_DIR=${BUILD_DIR:-build}
"$BUILD_DIR"/pepper_app/pepper_app version
