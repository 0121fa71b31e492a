#!/usr/bin/env bash
# CTest driver of the browser-side tests (tests/web/CMakeLists.txt). Exits 77 (CTest: Skipped) with a
# message when a tool is missing: em++ (emscripten), node, chromium, web/node_modules (npm ci in web/),
# all installed by scripts/install-web-deps.sh.
#   web_test.sh build OBJ_DIR                                  the wasm engine (web/build.sh, incremental)
#   web_test.sh wasm REFERENCE_EXE OUT_PREFIX MODEL NODE [reference options]   wasm = native trace
#   web_test.sh tool MEDSPRING_EXE OUT_DIR MODEL PATH TOOL_SPEC FRICTION   wasm = native, a rigid tool
#   web_test.sh api MODELS_DIR                                 the JS API of the engine (node)
#   web_test.sh page MEDSPRING_EXE OUT_DIR MODELS_DIR          the page in headless chromium (Playwright)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
web="$root/web"
export NODE_PATH="${NODE_PATH:-/usr/share/nodejs}"
skip() { echo "SKIP: $*"; exit 77; }
need_node() {
  command -v node >/dev/null || skip "node not found (apt-get install nodejs; scripts/install-web-deps.sh)"
  [[ -f "$web/dist/medspring.mjs" ]] || skip "web/dist/medspring.mjs not built (em++ missing? bash web/build.sh)"
}
mode="${1:?mode}"
shift
case "$mode" in
  build)
    command -v em++ >/dev/null || skip "em++ not found (apt-get install --no-install-recommends emscripten; scripts/install-web-deps.sh)"
    exec bash "$web/build.sh" "$1"
    ;;
  wasm)
    need_node
    exe="$1" out="$2" model="$3" node="$4"
    shift 4
    if [[ "$model" == *.msm && ! -f "$model" ]]; then
      echo "FAIL: $model missing: medspring export --web did not write it (the real anatomy needs \$MEDSPRING_DATA)"
      exit 1
    fi
    mkdir -p "$(dirname "$out")"
    ref=() js=()
    while (( $# )); do
      case "$1" in
        --trajectory) traj="$2"; ref+=(--trajectory "$2"); shift 2 ;;
        --press) traj="$out.trajectory.csv"; ref+=(--press "$2" --out-trajectory "$traj"); shift 2 ;;
        --params) ref+=(--params "$2"); js+=(--params "$2"); shift 2 ;;
        --linear|--local) ref+=("$1"); js+=("$1"); shift ;;
        *) echo "web_test.sh: unknown option $1" >&2; exit 2 ;;
      esac
    done
    "$exe" "$model" --node "$node" "${ref[@]}" --out-trace "$out.native.csv"
    exec node "$web/test/wasm_matches_native.mjs" "$traj" "$out.native.csv" "$node" "$model" "${js[@]}"
    ;;
  tool)
    need_node
    exe="$1" out="$2" model="$3" path="$4" spec="$5" friction="$6"
    "$exe" haptics "$model" --trajectory "$path" --tool "$spec" --friction "$friction" --out "$out" --force
    exec node "$web/test/wasm_tool_matches_native.mjs" "$path" "$out/force_trace.csv" "$model" "$spec" "$friction"
    ;;
  api)
    need_node
    exec node "$web/test/engine_api_test.mjs" "$1"
    ;;
  page)
    need_node
    chromium="${CHROMIUM:-/usr/bin/chromium}"
    [[ -x "$chromium" ]] || skip "$chromium not found (apt-get install --no-install-recommends chromium)"
    [[ -d "$web/node_modules/playwright-core" && -d "$web/node_modules/three" ]] ||
      skip "web/node_modules missing (cd web && npm ci; scripts/install-web-deps.sh)"
    exec node "$web/test/page_test.mjs" --medspring "$1" --out "$2" --models "$3" --chromium "$chromium"
    ;;
  *) echo "web_test.sh: unknown mode $mode" >&2; exit 2 ;;
esac
