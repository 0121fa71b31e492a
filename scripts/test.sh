#!/usr/bin/env bash
# Installs dependencies, builds everything and runs every test (C++ through CTest, Python through pytest).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build}
bash "$root/scripts/install-deps.sh"
bash "$root/scripts/install-web-deps.sh" || echo "test: web tools not installed: the web tests will be skipped" >&2
bash "$root/scripts/build.sh" -DMEDSPRING_BUILD_TESTS=ON -DMEDSPRING_BUILD_BENCH=ON
# A fresh tree gets the measured test costs, so CTest starts the longest tests first (scripts/ctest_costs.py).
costs=$build/Testing/Temporary/CTestCostData.txt
[ -f "$costs" ] || { mkdir -p "$(dirname "$costs")" && cp "$root/tests/ctest-costs/plain.txt" "$costs"; }
ctest --test-dir "$build" --output-on-failure --parallel "${JOBS:-$(nproc)}" --timeout 600
if [ -d "$root/python/tests" ]; then
  # one pytest worker per core (pytest-xdist, installed above): the Python suite ran on one core of two
  par=()
  /usr/bin/python3 -c "import xdist" 2>/dev/null && par=(-n "${JOBS:-$(nproc)}")
  PYTHONPATH="$build/python:${PYTHONPATH:-}" /usr/bin/python3 -m pytest -q "${par[@]}" "$root/python/tests"
fi
