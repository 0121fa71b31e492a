#!/usr/bin/env bash
# Installs MedSpring's build and run dependencies from Debian 12's archive (idempotent; run as root).
set -euo pipefail
PACKAGES=(
  g++ cmake ninja-build pkg-config git
  libeigen3-dev                      # engine: linear algebra
  libvtk9-dev                        # io: mesh/image formats, isosurfaces, rendering
  libcgal-dev libgmp-dev libmpfr-dev # meshing: isotropic remeshing
  nlohmann-json3-dev                 # CLI and scenes: JSON
  libgtest-dev libgmock-dev libbenchmark-dev
  pybind11-dev python3-dev python3-numpy python3-pytest python3-scipy python3-matplotlib
  xvfb xauth                         # offscreen rendering of the report figures (VTK under Xvfb)
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
