#!/usr/bin/env bash
# Installs what the browser side needs (docs/web.md), idempotently: Debian's emscripten (the wasm engine)
# and chromium (the page tests), node/npm where absent, and web/node_modules (npm ci: three, playwright-core).
# Without them the web tests are skipped (CTest "Skipped"), nothing else depends on them.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
pkgs=(emscripten chromium)
command -v node >/dev/null || pkgs+=(nodejs)
command -v npm >/dev/null || pkgs+=(npm)
bash "$root/scripts/apt-install.sh" install-web-deps "${pkgs[@]}"
# three and playwright-core at the versions of web/package-lock.json (never `playwright install`: the
# tests use Debian's /usr/bin/chromium).
web="$root/web"
if [ ! -d "$web/node_modules/three" ] || [ ! -d "$web/node_modules/playwright-core" ] ||
   [ "$web/package-lock.json" -nt "$web/node_modules/.package-lock.json" ]; then
  echo "install-web-deps: npm ci in web/"
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error)
else
  echo "install-web-deps: web/node_modules up to date"
fi
