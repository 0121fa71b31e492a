#!/usr/bin/env bash
# Builds the engine and its tests with AddressSanitizer + UndefinedBehaviorSanitizer into
# ${BUILD_DIR:-build-asan} and runs the engine tests (CTest label `engine`). Any report fails the run.
# Extra arguments go to ctest (e.g. -R sim_tests). Not part of scripts/test.sh (CI time; see
# docs/reliability.md for the figures).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build-asan}
jobs=${JOBS:-$(nproc)}
start=$(date +%s)
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DPython3_EXECUTABLE=/usr/bin/python3 \
  -DMEDSPRING_SANITIZE=ON -DMEDSPRING_WITH_VTK=OFF -DMEDSPRING_BUILD_BENCH=OFF \
  -DMEDSPRING_BUILD_PYTHON=OFF -DMEDSPRING_BUILD_TESTS=ON
cmake --build "$build" --parallel "$jobs"
built=$(date +%s)
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
ctest --test-dir "$build" -L engine --output-on-failure --parallel "$jobs" --timeout 1200 "$@"
end=$(date +%s)
echo "sanitize.sh: build $((built - start)) s, tests $((end - built)) s"
