#!/usr/bin/env bash
# Installs the Debian 12 packages samp needs, only those that are missing.
# Needs root (or sudo) when something is missing. Safe to run repeatedly.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libassimp-dev libembree-dev libopenvdb-dev libboost-iostreams-dev libopenvdb-tools
  libeigen3-dev libspectra-dev libceres-dev libtbb-dev libopencv-dev
  libcli11-dev nlohmann-json3-dev libgtest-dev libgmock-dev libbenchmark-dev
  # blosc and zlib: samp's own decoder of .vdb payloads (libsamp/sdf/vdb_payload.cc).
  libblosc-dev zlib1g-dev unzip
  # The HTML viewers embed Debian's three.js at build time (docs/fitting.md, "Viewer");
  # the browser test (tests/viz/html_viewer_test.cc) opens them in headless Chromium.
  libjs-three chromium
  # The Python package samp (libsamp/python, docs/python.md): pybind11 bindings for
  # Debian's python3, its tests (pytest), the Dask batch driver and the plotting example.
  pybind11-dev python3-dev python3-numpy python3-pytest python3-distributed python3-matplotlib
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "samp: all Debian packages present"
  exit 0
fi
echo "samp: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
