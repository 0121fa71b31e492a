#!/usr/bin/env bash
# The Python install of the README, tested as written, outside the source tree (CTest package.python_wheel):
# a wheel built with pip from this build tree (MEDSPRING_CMAKE_BUILD_DIR: no second CMake build), installed
# into a fresh virtual environment that sees Debian's numpy (--system-site-packages), imported there, and
# one example run with it.
#   tests/consumer/python_wheel.sh <source dir> <build dir> <work dir>
set -euo pipefail
src=$1 build=$2 work=$3
python=/usr/bin/python3
rm -rf "$work"
mkdir -p "$work"
cd "$work"

MEDSPRING_CMAKE_BUILD_DIR="$build" "$python" -m pip wheel --no-build-isolation --no-deps -w "$work/dist" "$src"
wheel=$(ls "$work"/dist/medspring-*.whl)
"$python" -m venv --system-site-packages "$work/venv"
"$work/venv/bin/python" -m pip install --no-index --no-deps "$wheel"

"$work/venv/bin/python" - "$work/venv" <<'PY'
import sys
import medspring as ms
assert ms.__file__.startswith(sys.argv[1]), f"medspring imported from {ms.__file__}, not the venv"
sim = ms.Simulation(ms.hybrid_kidney_phantom())
sim.set_loads([ms.PointLoad(node=223, force=(0, 0, -1.0), t_ramp=20, t_release=500)])
rest = sim.surface[223].copy()
sim.update(nsteps=400)  # 200 ms, pressed
depth = rest[2] - sim.surface[223][2]
assert depth > 0.1, f"node 223 pressed only {depth} mm"
print(f"venv: medspring {ms.__version__} from {ms.__file__}: node 223 pressed {depth:.3f} mm")
PY
"$work/venv/bin/python" "$src/examples/python/fit_spring_parameters.py" --out "$work/out"
ls "$work/out"/*.png
