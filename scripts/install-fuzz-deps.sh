#!/usr/bin/env bash
# Installs what the fuzz and sanitizer builds need on top of scripts/install-deps.sh, from Debian 12's
# archive (idempotent; run as root): clang 14 and its compiler-rt (libFuzzer, ASan, UBSan runtimes).
set -euo pipefail
PACKAGES=(clang-14 libclang-rt-14-dev)
bash "$(dirname "$0")/apt-install.sh" install-fuzz-deps "${PACKAGES[@]}"
