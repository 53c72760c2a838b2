#!/usr/bin/env bash
# Installs missing dependencies, configures and builds samp into build/ (or $SAMP_BUILD_DIR).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${SAMP_BUILD_DIR:-$root/build}"
bash "$root/tools/install_deps.sh"
# ccache, when installed, keeps rebuilds of unchanged sources cheap (SAMP_NO_CCACHE=1: off).
launcher=()
if [ -z "${SAMP_NO_CCACHE:-}" ] && command -v ccache >/dev/null; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" ${SAMP_CMAKE_ARGS:-}
cmake --build "$build" -j "$(nproc)"
