#!/usr/bin/env bash
# Compiles the Eigen-only engine layers (core geometry physics local medial models tools sim) and the embind
# API (web/src/*.cpp: the Engine in engine.cpp / engine_tools.cpp, bound in bindings.cpp) to WebAssembly
# with Debian's emscripten: web/dist/medspring.mjs (ES module, wasm embedded: -sSINGLE_FILE, so node and
# the browser load it without fetch).
# Usage: bash web/build.sh [BUILD_DIR]   (objects in BUILD_DIR, default build-wasm; incremental)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(dirname "$here")"
build="${1:-$root/build-wasm}"
export NODE_PATH="${NODE_PATH:-/usr/share/nodejs}"  # em++ needs acorn (TOOLCHAIN.md)
command -v em++ >/dev/null || { echo "web/build.sh: em++ not found (apt-get install emscripten)" >&2; exit 1; }
mkdir -p "$build/obj" "$here/dist"
flags=(-std=c++20 -O3 -DNDEBUG -fexceptions -I"$root/include" -I/usr/include/eigen3 -DEIGEN_MPL2_ONLY)
# Eigen and the standard headers, precompiled once with the same flags (about a second of each of the ~60
# compiles; the rest is template instantiation, which a precompiled header does not save)
pch="$build/obj/pch.hpp"
# (made again when this script or emscripten is newer: a header precompiled by another compiler is refused)
if [[ ! -f "$pch.pch" || "$here/build.sh" -nt "$pch.pch" || "$(readlink -f "$(command -v em++)")" -nt "$pch.pch" ]]; then
  printf '%s\n' '#include <Eigen/Dense>' '#include <Eigen/Sparse>' '#include <algorithm>' '#include <cmath>' \
    '#include <functional>' '#include <memory>' '#include <sstream>' '#include <stdexcept>' '#include <string>' \
    '#include <vector>' > "$pch"
  em++ "${flags[@]}" -x c++-header "$pch" -o "$pch.pch.tmp"
  mv "$pch.pch.tmp" "$pch.pch"
fi
flags+=(-include-pch "$pch.pch")
objs=()
jobs=0
for layer in core geometry physics local medial models tools sim; do
  for src in "$root"/src/$layer/*.cpp; do
    obj="$build/obj/$layer-$(basename "${src%.cpp}").o"
    objs+=("$obj")
    if [[ ! -f "$obj" || "$src" -nt "$obj" || "$pch.pch" -nt "$obj" ||
          -n "$(find "$root/include" -newer "$obj" -name '*.hpp' -print -quit)" ]]; then
      em++ "${flags[@]}" -c "$src" -o "$obj" &
      jobs=$((jobs + 1))
      if (( jobs >= ${WASM_JOBS:-2} )); then wait -n; jobs=$((jobs - 1)); fi
    fi
  done
done
while (( jobs > 0 )); do wait -n; jobs=$((jobs - 1)); done  # fails the script if a compile failed
# The JavaScript API: web/src/*.cpp (bindings.cpp binds the Engine of engine.hpp / engine*.cpp).
wobjs=()
for src in "$here"/src/*.cpp; do
  obj="$build/obj/web-$(basename "${src%.cpp}").o"
  wobjs+=("$obj")
  if [[ ! -f "$obj" || "$src" -nt "$obj" || "$pch.pch" -nt "$obj" ||
        -n "$(find "$root/include" "$here/src" -newer "$obj" -name '*.hpp' -print -quit)" ]]; then
    em++ "${flags[@]}" -c "$src" -o "$obj" &
    jobs=$((jobs + 1))
    if (( jobs >= ${WASM_JOBS:-2} )); then wait -n; jobs=$((jobs - 1)); fi
  fi
done
while (( jobs > 0 )); do wait -n; jobs=$((jobs - 1)); done
out="$here/dist/medspring.mjs"
relink=0
[[ -f "$out" ]] || relink=1
for o in "${objs[@]}" "${wobjs[@]}"; do [[ "$o" -nt "$out" ]] && relink=1; done
if (( relink )); then
  em++ -O3 "${objs[@]}" "${wobjs[@]}" -lembind -o "$out" \
    -sMODULARIZE=1 -sEXPORT_ES6=1 -sEXPORT_NAME=createMedSpring -sALLOW_MEMORY_GROWTH=1 -sSINGLE_FILE=1 \
    -sENVIRONMENT=web,node -fexceptions
  echo "web/build.sh: wrote $out"
else
  echo "web/build.sh: $out is up to date"
fi
