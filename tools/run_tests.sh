#!/usr/bin/env bash
# README command 2: install, build and run every unit test (ctest).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${SAMP_BUILD_DIR:-$root/build}"
bash "$root/tools/build.sh"
cd "$build"
ctest --output-on-failure -j "$(nproc)"
