#!/usr/bin/env bash
# The CUDA backend's checks (docs/gpu.md).
#
#   scripts/gpu-check.sh compile      nvcc compiles the kernels for sm_90 (no GPU needed): resource report
#                                     (registers, stack, spills) into ${OUT:-build-gpu-check}/ptxas.txt and
#                                     SASS into kernels.sass. Fails on a compile error, a stack frame or a
#                                     spill. Run before each stop where no CI job compiles the kernels.
#   scripts/gpu-check.sh stage DIR    (on a machine with Eigen, GoogleTest and nlohmann_json) copies their
#                                     headers / sources into DIR (e.g. shared/gpu-deps) for a GPU machine
#                                     that has none of them.
#   scripts/gpu-check.sh full [DEPS]  (on the GPU machine) ONE prepared run of every GPU figure of issue 21
#                                     in about 8 minutes on an H100 (GPU_CHECK_BUDGET_S, default 480, caps
#                                     the stages): the engine-only build (no VTK/CGAL; the scene layer with
#                                     nlohmann_json from DEPS when the system has none), MEDSPRING_CUDA=ON;
#                                     then, each stage under its own timeout so that a slow one cannot eat
#                                     the others: (1) medspring_gpu_bench (= medspring bench --gpu: the tube
#                                     at 1.2k/120k/1M/16M nodes fp64 + fp32, the copy bandwidth, PyTorch and
#                                     the CPU engine in the same run, 8,448 kidneys with both kernels) into
#                                     $OUT/gpu-bench; (2) the GPU tests (GPU = CPU trajectories, the study's
#                                     batch path, the haptic loop against the CPU loop with tick times) as
#                                     GoogleTest XML in $OUT/xml; (3) the CPU-side kernel tests. Finally
#                                     scripts/gpu_summary.py writes $OUT/summary.json and $OUT/summary.md
#                                     (the issue's table, its targets met or not, every test and the figures
#                                     it recorded) -- also when a stage failed or ran out of time.
#   scripts/gpu-check.sh              compile, then full when nvidia-smi sees a GPU.
# GPU_CHECK_USE_DEPS=1 takes Eigen/GoogleTest/nlohmann_json from DEPS even where the system has them;
# GPU_CHECK_CONFIGURE_ONLY=1 stops `full` after configuring (both: to try the GPU machine's path here);
# GPU_BENCH_ARGS replaces the bench's arguments (default --batch 8448 --compact --models-per-thread 2,4: the
# kidney batch also with 2 and 4 models per thread, about 8 more batch runs); GPU_CHECK_BENCH_S its time limit
# (200). The packed table (--packed) packs each tube on the host first: give it with --sizes 1200,1000000.
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
  awk '/Compiling entry function/ { match($0, /(block_frame_kernel|substep_kernel|substep_models_kernel)I[fd](Lb[01]E|Li[0-9]E)+/); k = substr($0, RSTART, RLENGTH) }
       /bytes stack frame/ { match($0, /[0-9]+ bytes stack frame.*/); st = substr($0, RSTART) }
       /Used [0-9]+ registers/ { match($0, /Used [0-9]+ registers.*/); printf "  %-33s %s; %s\n", k, substr($0, RSTART), st }' \
    "$out/ptxas.txt" | tee "$out/resources.txt"
  if command -v "$(dirname "$nvcc")/cuobjdump" >/dev/null; then
    "$(dirname "$nvcc")/cuobjdump" -sass "$out/kernels.o" > "$out/kernels.sass"
    echo "SASS: $(grep -c '' "$out/kernels.sass") lines in $out/kernels.sass (LDL/STL: $(grep -cE 'LDL|STL' "$out/kernels.sass" || true))"
  fi
  # The trace reduction of the study's batch path (sample.cu), reported the same way.
  "$nvcc" -std=c++17 -O3 -gencode=arch=compute_90,code=sm_90 -I"$root/include" -I"$root/src/gpu" \
    -Xptxas -v -c "$root/src/gpu/sample.cu" -o "$out/sample.o" 2> "$out/ptxas-sample.txt"
  awk '/Compiling entry function/ { match($0, /trace_kernelI[fd]E/); k = substr($0, RSTART, RLENGTH) }
       /bytes stack frame/ { match($0, /[0-9]+ bytes stack frame.*/); st = substr($0, RSTART) }
       /Used [0-9]+ registers/ { match($0, /Used [0-9]+ registers.*/); printf "  %-26s %s; %s\n", k, substr($0, RSTART), st }' \
    "$out/ptxas-sample.txt" | tee -a "$out/resources.txt"
  if grep -E "[1-9][0-9]* bytes stack frame|[1-9][0-9]* bytes spill" "$out/ptxas.txt" "$out/ptxas-sample.txt"; then
    echo "gpu-check: a kernel uses a stack frame or spills (see $out/ptxas.txt)" >&2
    exit 1
  fi
  echo "gpu-check: kernels compile for sm_90, no stack frame, no spills"
}

stage() {
  local dir=${1:?usage: gpu-check.sh stage DIR}
  mkdir -p "$dir"
  rm -rf "$dir/eigen3" "$dir/googletest" "$dir/json-include"  # idempotent: cp -r into an existing dir nests
  cp -r /usr/include/eigen3 "$dir/eigen3"
  cp -r /usr/src/googletest "$dir/googletest"
  mkdir -p "$dir/json-include" && cp -r /usr/include/nlohmann "$dir/json-include/nlohmann"
  # The real kidney as a model package (the GPU machine has no data folder): the hybrid kidney of the
  # bundled scene, built here with the CLI when it and the data are present.
  local cli=${MEDSPRING_CLI:-$root/build/apps/medspring}
  if [ -x "$cli" ]; then
    rm -rf "$dir/kidney-export"
    if "$cli" export --quiet --out "$dir/kidney-export" "$root/scenes/kidney_0.2N_nonlinear.json" > /dev/null &&
      mv "$dir/kidney-export/kidney_0.2N_nonlinear.msm" "$dir/kidney.msm"; then
      echo "gpu-check: staged the real kidney's model package in $dir/kidney.msm"
    else
      echo "gpu-check: no real kidney package (export failed: data folder? see MEDSPRING_DATA)"
    fi
    rm -rf "$dir/kidney-export"
  fi
  echo "gpu-check: staged Eigen, GoogleTest and nlohmann_json in $dir ($(du -sh "$dir" | cut -f1))"
}

# run_stage NAME LIMIT_S CMD...: runs CMD into $out/logs/NAME.log under min(LIMIT_S, what is left of the
# budget) and appends "NAME<TAB>exit<TAB>seconds" to $out/stages.tsv; never stops the script.
run_stage() {
  local name=$1 limit=$2
  shift 2
  local left=$((budget - (SECONDS - start)))
  ((left < limit)) && limit=$left
  if ((limit < 10)); then
    printf '%s\t%s\t0\n' "$name" "skipped: budget spent" >> "$out/stages.tsv"
    echo "gpu-check: $name skipped (budget of ${budget} s spent)"
    return 0
  fi
  local t0=$SECONDS rc=0
  echo "gpu-check: $name (at most ${limit} s) ..."
  timeout --kill-after=10 "$limit" "$@" > "$out/logs/$name.log" 2>&1 || rc=$?
  printf '%s\t%s\t%s\n' "$name" "$rc" "$((SECONDS - t0))" >> "$out/stages.tsv"
  echo "gpu-check: $name exit $rc in $((SECONDS - t0)) s ($out/logs/$name.log)"
  tail -5 "$out/logs/$name.log" || true
}

# want STAGE: whether GPU_CHECK_STAGES (comma-separated; default every stage but python) selects STAGE.
want() { [[ ",${GPU_CHECK_STAGES:-bench,gpu_tests,gpu_scene_tests,cpu_kernel_tests,hybrid_gather_tests}," == *",$1,"* ]]; }

full() {
  local deps=${1:-$root/shared/gpu-deps}
  [ ! -d "$deps" ] || deps=$(cd "$deps" && pwd)  # CMake refuses relative include directories
  # The build and the copied dependencies go to GPU_CHECK_WORK (default $out): on the device machine put
  # them outside the folder whose files come back.
  local work=${GPU_CHECK_WORK:-$out}
  local build=$work/build prefix=$work/deps skip="fem;paper"
  budget=${GPU_CHECK_BUDGET_S:-480}
  start=$SECONDS
  mkdir -p "$out/logs" "$out/xml" "$work"
  : > "$out/stages.tsv"
  local python_on=OFF
  want python && python_on=ON
  local args=(-DMEDSPRING_WITH_VTK=OFF -DMEDSPRING_WITH_CGAL=OFF "-DMEDSPRING_BUILD_PYTHON=$python_on"
    -DMEDSPRING_BUILD_BENCH=OFF -DMEDSPRING_CUDA=ON -DCMAKE_CUDA_COMPILER="$nvcc")
  if [ $python_on = ON ]; then
    # The machine's own python3 (the one with PyTorch / CuPy) and its pip-installed pybind11.
    args+=(-DPython3_EXECUTABLE="$(command -v python3)" -Dpybind11_DIR="$(python3 -m pybind11 --cmakedir || true)")
  fi
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
  # nlohmann_json (header-only) for the scene layer: the study's batch path on the GPU (gpu_scene_tests).
  if [ -n "${GPU_CHECK_USE_DEPS:-}" ] || ! ls /usr/share/cmake/nlohmann_json/nlohmann_jsonConfig.cmake \
      /usr/lib/cmake/nlohmann_json/nlohmann_jsonConfig.cmake \
      /usr/local/share/cmake/nlohmann_json/nlohmann_jsonConfig.cmake >/dev/null 2>&1; then
    if [ -d "$deps/json-include/nlohmann" ]; then
      mkdir -p "$prefix/json-cmake"
      cat > "$prefix/json-cmake/nlohmann_jsonConfig.cmake" <<EOF
set(nlohmann_json_VERSION 3.11.2)
if(NOT TARGET nlohmann_json::nlohmann_json)
  add_library(nlohmann_json::nlohmann_json INTERFACE IMPORTED)
  set_target_properties(nlohmann_json::nlohmann_json PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "$deps/json-include")
endif()
EOF
      printf 'set(PACKAGE_VERSION 3.11.2)\nset(PACKAGE_VERSION_COMPATIBLE TRUE)\n' > "$prefix/json-cmake/nlohmann_jsonConfigVersion.cmake"
      args+=(-Dnlohmann_json_DIR="$prefix/json-cmake")
    else
      echo "gpu-check: no nlohmann_json here or in $deps: the scene layer (the study's batch path) is left out"
      skip="scene;fem;paper"
    fi
  fi
  args+=(-DMEDSPRING_SKIP_LAYERS="$skip")
  if [ -n "${GPU_CHECK_USE_DEPS:-}" ] || ! ls /usr/lib/*/cmake/GTest/GTestConfig.cmake /usr/local/lib/cmake/GTest/GTestConfig.cmake >/dev/null 2>&1; then
    [ -d "$deps/googletest" ] || { echo "gpu-check: no GoogleTest here and none in $deps" >&2; exit 2; }
    cmake -S "$deps/googletest" -B "$work/gtest-build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_INSTALL_PREFIX="$prefix/gtest" -DBUILD_GMOCK=OFF > "$out/gtest.log"
    cmake --build "$work/gtest-build" >> "$out/gtest.log" && cmake --install "$work/gtest-build" >> "$out/gtest.log"
    args+=(-DGTest_DIR="$(dirname "$(find "$prefix/gtest" -name GTestConfig.cmake | head -1)")")
  fi
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${args[@]}" > "$out/configure.log"
  grep -E "MedSpring: CUDA|Eigen|GTest|Python package" "$out/configure.log" || true
  [ -z "${GPU_CHECK_CONFIGURE_ONLY:-}" ] || return 0
  nvidia-smi --query-gpu=name,memory.total,driver_version,clocks.max.sm --format=csv > "$out/nvidia-smi.csv" 2>&1 || true
  local targets=()
  want bench && targets+=(medspring_gpu_bench)
  want gpu_tests && targets+=(gpu_tests)
  want gpu_scene_tests && grep -q "gpu_scene_tests" "$build/build.ninja" 2>/dev/null && targets+=(gpu_scene_tests)
  want cpu_kernel_tests && targets+=(physics_tests)
  want hybrid_gather_tests && targets+=(hybrid_gather_tests)
  if want python; then
    if grep -q "medspring_python" "$build/build.ninja" 2>/dev/null; then
      targets+=(medspring_python)
    else
      echo "gpu-check: the Python package is not part of this build (see $out/configure.log): python stage skipped"
      GPU_CHECK_STAGES=${GPU_CHECK_STAGES//python/}
    fi
  fi
  run_stage build 300 cmake --build "$build" --target "${targets[@]}"
  # The real kidney (staged by `stage` as a model package) for the GPU tests and the batch case.
  local kidney_args=()
  if [ -f "$deps/kidney.msm" ]; then
    export MEDSPRING_GPU_KIDNEY="$deps/kidney.msm"
    kidney_args=(--kidney "$deps/kidney.msm")
  fi
  # (1) the issue's table: tube sizes, precisions, bandwidth, PyTorch and CPU, the kidney batch.
  # shellcheck disable=SC2086
  want bench && run_stage bench "${GPU_CHECK_BENCH_S:-200}" "$build/bench/medspring_gpu_bench" --out "$out/gpu-bench" \
    ${GPU_BENCH_ARGS:---batch 8448 --compact --models-per-thread 2,4} "${kidney_args[@]}"
  # (2) GPU against CPU, the study's batch path, the haptic loops (figures recorded in the XML and log).
  # shellcheck disable=SC2086
  want gpu_tests && run_stage gpu_tests 180 "$build/tests/gpu/gpu_tests" ${GPU_TESTS_ARGS:-} \
    --gtest_output="xml:$out/xml/gpu_tests.xml"
  if want gpu_scene_tests && [ -x "$build/tests/gpu/gpu_scene_tests" ]; then
    run_stage gpu_scene_tests 90 "$build/tests/gpu/gpu_scene_tests" --gtest_output="xml:$out/xml/gpu_scene_tests.xml"
  fi
  # (3) the CPU-side twins of the kernels (block kernel, its split rows, the grid kernel's split rows).
  want cpu_kernel_tests && run_stage cpu_kernel_tests 60 "$build/tests/physics/physics_tests" \
    --gtest_filter='HdKernels*:SpringTable*:HdModels*:PackedTable*' --gtest_output="xml:$out/xml/physics_tests.xml"
  want hybrid_gather_tests && run_stage hybrid_gather_tests 60 "$build/tests/models/hybrid_gather_tests" \
    --gtest_output="xml:$out/xml/hybrid_gather_tests.xml"
  # (4) optional (GPU_CHECK_STAGES=...,python): medspring.gpu from Python, (B, N, 3) arrays and DLPack
  # hand-over to CuPy / PyTorch (python/tests/test_gpu.py) and the study on the GPU (test_study_device.py),
  # with the machine's python3.
  want python && run_stage python 120 env PYTHONPATH="$build/python" python3 -m pytest -q -rs \
    "$root/python/tests/test_gpu.py" "$root/python/tests/test_study_device.py" --junitxml="$out/xml/python_gpu.xml"
  python3 "$root/scripts/gpu_summary.py" "$out" > "$out/logs/summary.log" 2>&1 ||
    echo "gpu-check: summary failed (see $out/logs/summary.log)"
  head -40 "$out/summary.md" 2>/dev/null || true
  echo "gpu-check: full done in $((SECONDS - start)) s; $out/summary.md, $out/summary.json"
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
