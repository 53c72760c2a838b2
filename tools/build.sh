#!/usr/bin/env bash
# Installs missing dependencies, configures and builds samp into build/ (or $SAMP_BUILD_DIR).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${SAMP_BUILD_DIR:-$root/build}"
bash "$root/tools/install_deps.sh"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release ${SAMP_CMAKE_ARGS:-}
cmake --build "$build" -j "$(nproc)"
