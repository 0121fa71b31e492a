#!/usr/bin/env bash
# The main job: install dependencies, build, and run the paper's experiments on the bundled default
# (real anatomy from ${MEDSPRING_DATA:-../shared/data}; procedural phantoms where it is absent).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/install-deps.sh"
bash "$root/scripts/build.sh" -DMEDSPRING_BUILD_TESTS=OFF -DMEDSPRING_BUILD_BENCH=OFF
bin=${BUILD_DIR:-$root/build}/apps/medspring
out=${OUT:-$root/out}
if "$bin" --help | grep -q "^  paper "; then
  "$bin" paper --out "$out/paper" --force "$@"
else
  "$bin" demo "$@"
  "$bin" bench --quick
fi
