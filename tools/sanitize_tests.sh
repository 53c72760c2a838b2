#!/usr/bin/env bash
# The sanitizer pass of CI (.ci/run): builds the library, the samp tool, the
# unit tests and the fuzz targets with clang, AddressSanitizer (with
# LeakSanitizer) and UndefinedBehaviorSanitizer into build-sanitize/ (or
# $SAMP_SANITIZE_BUILD_DIR), without the benchmarks, and runs ctest. Any
# sanitizer report fails the test that produced it (halt_on_error; a leak
# fails at exit). tools/fuzz.sh fuzzes with the same build. Third-party leaks
# that are not samp's are listed with their reason in tests/sanitizer/lsan.supp,
# undefined behaviour inside third-party headers in tests/sanitizer/ubsan.supp.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${SAMP_SANITIZE_BUILD_DIR:-$root/build-sanitize}"
bash "$root/tools/install_deps.sh"
if ! command -v clang++ >/dev/null; then
  sudo_cmd=(); [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends clang libclang-rt-dev
fi
launcher=()
if [ -z "${SAMP_NO_CCACHE:-}" ] && command -v ccache >/dev/null; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ "${launcher[@]}" \
  "-DSAMP_SANITIZE=address;undefined" -DSAMP_FUZZ=ON -DSAMP_BUILD_BENCHMARKS=OFF ${SAMP_CMAKE_ARGS:-}
if [ "${1:-}" = "--configure-only" ]; then exit 0; fi
cmake --build "$build" -j "$(nproc)" ${SAMP_SANITIZE_TARGETS:+--target $SAMP_SANITIZE_TARGETS}
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$root/tests/sanitizer/ubsan.supp:${UBSAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$root/tests/sanitizer/lsan.supp:${LSAN_OPTIONS:-}"
cd "$build"
ctest --output-on-failure -j "$(nproc)" ${SAMP_SANITIZE_CTEST_ARGS:-}
