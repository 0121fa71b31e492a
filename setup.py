"""Builds the `medspring` Python package by driving CMake (see pyproject.toml).

The compiled module comes from the CMake target medspring_python (python/CMakeLists.txt), built in
build-pip/ (or $MEDSPRING_PIP_BUILD_DIR) with the interpreter running this script; the pure-Python part
is python/medspring. Extra CMake options go in $CMAKE_ARGS (e.g. "-DMEDSPRING_WITH_CGAL=OFF"), the
number of parallel jobs in $JOBS.

With $MEDSPRING_CMAKE_BUILD_DIR set to an already configured build tree (e.g. build/ of
scripts/build.sh, configured with the same interpreter), that tree is reused instead: only the target
medspring_python is brought up to date there (nothing to do after a full build), and setuptools' own
scratch files go to <that tree>/python-wheel instead of build-pip/ (docs/packaging.md).
"""

import os
import shlex
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
REUSE = os.environ.get("MEDSPRING_CMAKE_BUILD_DIR")
SCRATCH = Path(REUSE).resolve() / "python-wheel" if REUSE else Path("build-pip")


class CMakeExtension(Extension):
    def __init__(self, name: str, target: str):
        super().__init__(name, sources=[])
        self.target = target


class CMakeBuild(build_ext):
    def build_extension(self, ext: CMakeExtension) -> None:
        if REUSE:
            build = Path(REUSE).resolve()
            if not (build / "CMakeCache.txt").is_file():
                raise RuntimeError(f"MEDSPRING_CMAKE_BUILD_DIR={REUSE}: not a configured CMake build tree")
            self.build_target(build, ext)
            return
        build = Path(os.environ.get("MEDSPRING_PIP_BUILD_DIR", ROOT / "build-pip")).resolve()
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(build), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython3_EXECUTABLE={sys.executable}", "-DMEDSPRING_BUILD_TESTS=OFF", "-DMEDSPRING_BUILD_BENCH=OFF",
            "-DMEDSPRING_BUILD_PYTHON=ON",
        ] + shlex.split(os.environ.get("CMAKE_ARGS", ""))
        subprocess.run(configure, check=True)
        self.build_target(build, ext)

    def build_target(self, build: Path, ext: CMakeExtension) -> None:
        cache = (build / "CMakeCache.txt").read_text(errors="replace")
        if "\nBUILD_SHARED_LIBS:BOOL=ON" in cache:  # the module would need libmedspring_*.so beside it
            raise RuntimeError(f"{build} builds shared libraries (BUILD_SHARED_LIBS=ON): the Python package "
                               "needs the default static build")
        jobs = os.environ.get("JOBS", str(os.cpu_count() or 1))
        subprocess.run(["cmake", "--build", str(build), "--target", ext.target, "--parallel", jobs], check=True)
        suffix = sysconfig.get_config_var("EXT_SUFFIX")  # the module must be built for this interpreter
        built = sorted((build / "python" / "medspring").glob("_medspring*.so"))
        if not built:
            raise RuntimeError(f"CMake did not produce {build}/python/medspring/_medspring*.so")
        if not built[-1].name.endswith(suffix):
            raise RuntimeError(f"{built[-1]} is not built for {sys.executable} (*{suffix}): configure {build} "
                               f"with -DPython3_EXECUTABLE={sys.executable}")
        dest = Path(self.get_ext_fullpath(ext.name))
        dest.parent.mkdir(parents=True, exist_ok=True)
        self.copy_file(str(built[-1]), str(dest))


SCRATCH.mkdir(parents=True, exist_ok=True)  # egg_info needs its folder to exist
setup(
    packages=["medspring", "medspring.study"],
    package_dir={"medspring": "python/medspring"},
    ext_modules=[CMakeExtension("medspring._medspring", target="medspring_python")],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": str(SCRATCH / "setuptools")}, "egg_info": {"egg_base": str(SCRATCH)}},
    zip_safe=False,
)
