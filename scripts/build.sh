#!/usr/bin/env bash
# Configures and builds MedSpring (Release) into ${BUILD_DIR:-build}. Extra arguments go to CMake.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build}
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DPython3_EXECUTABLE=/usr/bin/python3 "$@"
cmake --build "$build" --parallel "${JOBS:-$(nproc)}"
