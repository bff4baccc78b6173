#!/usr/bin/env bash
# Installs everything the project needs from Debian packages (and the npm registry for the browser
# test), non-interactively. Safe to run any number of times: it installs only what is missing.
#   scripts/setup.sh          install system packages and the browser-test node modules
#   scripts/setup.sh --check  only report what is missing (exit 1 if anything is)
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libopencv-dev libopencv-contrib-dev libeigen3-dev libvisp-dev libxml2-dev visp-images-data
  libboost-dev libboost-system-dev libssl-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev libyaml-cpp-dev
  clang libclang-rt-14-dev
  chromium python3
)
# node and npm: this image may already ship them outside Debian's packaging (then Debian's npm
# package conflicts); install Debian's only when the commands are missing.
if ! command -v node >/dev/null 2>&1; then PACKAGES+=(nodejs); fi
if ! command -v npm >/dev/null 2>&1; then PACKAGES+=(npm); fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [[ "${1:-}" == "--check" ]]; then
  if ((${#missing[@]})); then echo "missing: ${missing[*]}"; exit 1; fi
  echo "all packages present"; exit 0
fi

if ((${#missing[@]})); then
  echo "setup: installing ${#missing[@]} Debian package(s): ${missing[*]}"
  SUDO=""
  if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all ${#PACKAGES[@]} Debian packages present"
fi

# Browser test dependencies (playwright-core drives Debian's chromium; no browser download).
if [[ -f tests/ui/package.json ]]; then
  if [[ ! -d tests/ui/node_modules/playwright-core ]]; then
    echo "setup: installing browser-test node modules (npm)"
    (cd tests/ui && npm ci --no-audit --no-fund --loglevel=error)
  fi
fi
