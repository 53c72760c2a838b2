#!/usr/bin/env bash
# Builds samp's libFuzzer targets (tests/fuzz: clang, ASan + UBSan, libFuzzer)
# and runs each for a given time. Needs Debian's clang (installed if missing).
#
#   bash tools/fuzz.sh [--seconds N] [--runs N] [--seed N] [--work DIR] [TARGET ...]
#
#   --seconds N   run time per target (default 60)
#   --runs N      also stop a target after N executions (libFuzzer -runs)
#   --seed N      libFuzzer's random seed (default: a new one per run); CI fixes
#                 it so that a red run is reproduced by running it again
#   --work DIR    working folder: corpus copies, findings, logs
#                 (default ${SAMP_DATA_DIR:-~/.cache/samp}/fuzz)
#   TARGET        model_loader model_payload kitti_text mesh manifest png (default: all)
#
# Each target starts from a copy of tests/fuzz/corpus/TARGET (the repository's
# seeds are not modified) under a 1024 MB RSS limit, inputs up to 2 MB. A crash,
# sanitizer report, leak, timeout (> 10 s) or memory overrun is a finding: its input
# goes to WORK/TARGET/findings/; copy it into tests/fuzz/regressions/TARGET/ once
# fixed so that the ctest fuzz/TARGET.Replay keeps replaying it. Prints one line
# per target (executions, findings, peak RSS) and exits non-zero on any finding.
# The build is the sanitizer build of tools/sanitize_tests.sh (build-sanitize/,
# or $SAMP_SANITIZE_BUILD_DIR): clang, ASan + UBSan, libFuzzer coverage.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seconds=60
runs_limit=""
seed=""
work="${SAMP_DATA_DIR:-$HOME/.cache/samp}/fuzz"
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --runs) runs_limit="$2"; shift 2 ;;
    --seed) seed="$2"; shift 2 ;;
    --work) work="$2"; shift 2 ;;
    -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
[ ${#targets[@]} -gt 0 ] || targets=(model_loader model_payload kitti_text mesh manifest png)
case "$seconds" in ''|*[!0-9]*) echo "fuzz.sh: --seconds needs a whole number" >&2; exit 2 ;; esac
case "$runs_limit" in *[!0-9]*) echo "fuzz.sh: --runs needs a whole number" >&2; exit 2 ;; esac
case "$seed" in *[!0-9]*) echo "fuzz.sh: --seed needs a whole number" >&2; exit 2 ;; esac

build="${SAMP_SANITIZE_BUILD_DIR:-$root/build-sanitize}"
bash "$root/tools/sanitize_tests.sh" --configure-only >/dev/null
cmake --build "$build" -j "$(nproc)" --target "${targets[@]/#/fuzz_}"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$root/tests/sanitizer/lsan.supp}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1:suppressions=$root/tests/sanitizer/ubsan.supp}"
status=0
for target in "${targets[@]}"; do
  dir="$work/$target"
  mkdir -p "$dir/corpus" "$dir/findings"
  cp -n "$root/tests/fuzz/corpus/$target"/* "$dir/corpus/" 2>/dev/null || true
  log="$dir/fuzz.log"
  set +e
  "$build/tests/fuzz/fuzz_$target" "$dir/corpus" -max_total_time="$seconds" -rss_limit_mb=1024 \
    -malloc_limit_mb=1024 -max_len=2097152 -timeout=10 -print_final_stats=1 \
    ${runs_limit:+-runs=$runs_limit} ${seed:+-seed=$seed} -artifact_prefix="$dir/findings/" > "$log" 2>&1
  rc=$?
  set -e
  runs=$(grep -o '^stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  rss=$(grep -o '^stat::peak_rss_mb: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')
  findings=$(find "$dir/findings" -type f | wc -l)
  echo "fuzz $target: $runs executions (limit ${seconds} s${runs_limit:+ or $runs_limit runs}), peak RSS $rss MB, $findings findings (exit $rc, log $log)"
  if [ "$rc" -ne 0 ] || [ "$findings" -ne 0 ]; then status=1; fi
done
exit $status
