#!/usr/bin/env bash
# Installs MedSpring's build and run dependencies from Debian 12's archive (idempotent; run as root).
set -euo pipefail
PACKAGES=(
  g++ cmake ninja-build pkg-config git
  libeigen3-dev                      # engine: linear algebra
  zlib1g-dev                         # io: compressed MetaImage / NRRD data
  libvtk9-dev                        # io: mesh/image formats, isosurfaces, rendering
  libcgal-dev libgmp-dev libmpfr-dev # meshing: isotropic remeshing
  nlohmann-json3-dev                 # CLI and scenes: JSON
  libcli11-dev                       # CLI: the medspring command line (CLI11, header-only)
  libgtest-dev libgmock-dev libbenchmark-dev
  pybind11-dev python3-dev python3-numpy python3-pytest python3-scipy python3-matplotlib
  python3-pytest-xdist               # scripts/test.sh: pytest on every core (-n)
  xvfb xauth                         # offscreen rendering of the report figures (VTK under Xvfb)
  python3-jinja2                     # medspring paper: report.md rendered from results.json (scripts/paper/report.py)
  python3-distributed python3-dask python3-zarr python3-pandas python3-tqdm python3-xarray  # medspring study (Dask)
  python3-pip python3-venv python3-setuptools python3-wheel dpkg-dev make  # package tests: wheel, venv, .deb, pkg-config consumer
  calculix-ccx tetgen                # fem: the FEM reference (medspring accuracy / calibrate, fem tests)
  libbullet-dev                      # bench --compare only: Bullet's btSoftBody side by side
)
bash "$(dirname "$0")/apt-install.sh" install-deps "${PACKAGES[@]}"
