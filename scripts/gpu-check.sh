#!/usr/bin/env bash
# The CUDA backend's checks (docs/gpu.md).
#
#   scripts/gpu-check.sh compile      nvcc compiles the kernels for sm_90 (no GPU needed): resource report
#                                     (registers, stack, spills) into ${OUT:-build-gpu-check}/ptxas.txt and
#                                     SASS into kernels.sass. Fails on a compile error, a stack frame or a
#                                     spill. Run before each stop where no CI job compiles the kernels.
#   scripts/gpu-check.sh stage DIR    (on a machine with Eigen and GoogleTest) copies the Eigen headers and
#                                     the GoogleTest sources into DIR (e.g. shared/gpu-deps) for a GPU
#                                     machine that has neither.
#   scripts/gpu-check.sh full [DEPS]  (on the GPU machine) the engine-only build (no VTK/CGAL, no scene
#                                     layer: nlohmann_json absent) with MEDSPRING_CUDA=ON, Eigen and
#                                     GoogleTest from DEPS (default shared/gpu-deps) when the system has
#                                     none; runs the physics tests, the `gpu`-labelled tests, and
#                                     medspring_gpu_bench (= medspring bench --gpu) into $OUT/gpu-bench.
#   scripts/gpu-check.sh              compile, then full when nvidia-smi sees a GPU.
# GPU_CHECK_USE_DEPS=1 takes Eigen/GoogleTest from DEPS even where the system has them;
# GPU_CHECK_CONFIGURE_ONLY=1 stops `full` after configuring (both: to try the GPU machine's path here).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${OUT:-$root/build-gpu-check}
mkdir -p "$out"
nvcc=${CUDACXX:-$(command -v nvcc || echo /usr/local/cuda/bin/nvcc)}

compile() {
  [ -x "$nvcc" ] || { echo "gpu-check: no nvcc (set CUDACXX)" >&2; exit 2; }
  "$nvcc" --version | tail -2
  "$nvcc" -std=c++17 -O3 -gencode=arch=compute_90,code=sm_90 -I"$root/include" -I"$root/src/gpu" \
    -Xptxas -v -c "$root/src/gpu/kernels.cu" -o "$out/kernels.o" 2> "$out/ptxas.txt"
  # One line per kernel: name (template arguments: real type f/d, soft law, stiffening) and resources.
  awk '/Compiling entry function/ { match($0, /(block_frame_kernel|substep_kernel)I[fd](Lb[01]E)+/); k = substr($0, RSTART, RLENGTH) }
       /bytes stack frame/ { match($0, /[0-9]+ bytes stack frame.*/); st = substr($0, RSTART) }
       /Used [0-9]+ registers/ { match($0, /Used [0-9]+ registers.*/); printf "  %-26s %s; %s\n", k, substr($0, RSTART), st }' \
    "$out/ptxas.txt" | tee "$out/resources.txt"
  if command -v "$(dirname "$nvcc")/cuobjdump" >/dev/null; then
    "$(dirname "$nvcc")/cuobjdump" -sass "$out/kernels.o" > "$out/kernels.sass"
    echo "SASS: $(grep -c '' "$out/kernels.sass") lines in $out/kernels.sass (LDL/STL: $(grep -cE 'LDL|STL' "$out/kernels.sass" || true))"
  fi
  if grep -E "[1-9][0-9]* bytes stack frame|[1-9][0-9]* bytes spill" "$out/ptxas.txt"; then
    echo "gpu-check: a kernel uses a stack frame or spills (see $out/ptxas.txt)" >&2
    exit 1
  fi
  echo "gpu-check: kernels compile for sm_90, no stack frame, no spills"
}

stage() {
  local dir=${1:?usage: gpu-check.sh stage DIR}
  mkdir -p "$dir"
  cp -r /usr/include/eigen3 "$dir/eigen3"
  cp -r /usr/src/googletest "$dir/googletest"
  echo "gpu-check: staged Eigen and GoogleTest in $dir ($(du -sh "$dir" | cut -f1))"
}

full() {
  local deps=${1:-$root/shared/gpu-deps}
  local build=$out/build prefix=$out/deps
  local args=(-DMEDSPRING_WITH_VTK=OFF -DMEDSPRING_WITH_CGAL=OFF -DMEDSPRING_BUILD_PYTHON=OFF
    -DMEDSPRING_BUILD_BENCH=OFF -DMEDSPRING_SKIP_LAYERS="scene;fem" -DMEDSPRING_CUDA=ON
    -DCMAKE_CUDA_COMPILER="$nvcc")
  # GPU_CHECK_USE_DEPS=1 uses DEPS even where the system has Eigen/GoogleTest (to try this path anywhere).
  if [ -n "${GPU_CHECK_USE_DEPS:-}" ] || { [ ! -d /usr/include/eigen3 ] && [ ! -d /usr/local/include/eigen3 ]; }; then
    [ -d "$deps/eigen3" ] || { echo "gpu-check: no Eigen here and none in $deps (run 'stage' where Eigen is)" >&2; exit 2; }
    # Eigen is header-only: a minimal Eigen3Config.cmake pointing at the copied headers.
    mkdir -p "$prefix/eigen-cmake"
    cat > "$prefix/eigen-cmake/Eigen3Config.cmake" <<EOF
set(EIGEN3_VERSION_STRING 3.4.0)
set(Eigen3_VERSION 3.4.0)
if(NOT TARGET Eigen3::Eigen)
  add_library(Eigen3::Eigen INTERFACE IMPORTED)
  set_target_properties(Eigen3::Eigen PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "$deps/eigen3")
endif()
EOF
    printf 'set(PACKAGE_VERSION 3.4.0)\nset(PACKAGE_VERSION_COMPATIBLE TRUE)\n' > "$prefix/eigen-cmake/Eigen3ConfigVersion.cmake"
    args+=(-DEigen3_DIR="$prefix/eigen-cmake")
  fi
  if [ -n "${GPU_CHECK_USE_DEPS:-}" ] || ! ls /usr/lib/*/cmake/GTest/GTestConfig.cmake /usr/local/lib/cmake/GTest/GTestConfig.cmake >/dev/null 2>&1; then
    [ -d "$deps/googletest" ] || { echo "gpu-check: no GoogleTest here and none in $deps" >&2; exit 2; }
    cmake -S "$deps/googletest" -B "$out/gtest-build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_INSTALL_PREFIX="$prefix/gtest" -DBUILD_GMOCK=OFF > "$out/gtest.log"
    cmake --build "$out/gtest-build" >> "$out/gtest.log" && cmake --install "$out/gtest-build" >> "$out/gtest.log"
    args+=(-DGTest_DIR="$(dirname "$(find "$prefix/gtest" -name GTestConfig.cmake | head -1)")")
  fi
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${args[@]}" > "$out/configure.log"
  grep -E "MedSpring: CUDA|Eigen|GTest" "$out/configure.log" || true
  [ -z "${GPU_CHECK_CONFIGURE_ONLY:-}" ] || return 0
  cmake --build "$build" --target gpu_tests physics_tests hybrid_gather_tests medspring_gpu_bench
  ctest --test-dir "$build" -R 'HdKernels|SpringTable|HybridGather' --output-on-failure
  ctest --test-dir "$build" -L gpu --output-on-failure --timeout 1800
  "$build/bench/medspring_gpu_bench" --out "$out/gpu-bench" ${GPU_BENCH_ARGS:-}
}

case "${1:-auto}" in
  compile) compile ;;
  stage) stage "${2:-}" ;;
  full) full "${2:-}" ;;
  auto)
    compile
    if command -v nvidia-smi >/dev/null && nvidia-smi -L 2>/dev/null | grep -q GPU; then
      full
    else
      echo "gpu-check: no GPU here: kernels compiled only; GPU tests and bench --gpu not run"
    fi
    ;;
  *) echo "usage: gpu-check.sh [compile|stage DIR|full [DEPS]]" >&2; exit 2 ;;
esac
