"""Builds the `medspring` Python package by driving CMake (see pyproject.toml).

The compiled module comes from the CMake target medspring_python (python/CMakeLists.txt), built in
build-pip/ (or $MEDSPRING_PIP_BUILD_DIR) with the interpreter running this script; the pure-Python part
is python/medspring. Extra CMake options go in $CMAKE_ARGS (e.g. "-DMEDSPRING_WITH_CGAL=OFF"), the
number of parallel jobs in $JOBS.
"""

import os
import shlex
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


class CMakeExtension(Extension):
    def __init__(self, name: str, target: str):
        super().__init__(name, sources=[])
        self.target = target


class CMakeBuild(build_ext):
    def build_extension(self, ext: CMakeExtension) -> None:
        build = Path(os.environ.get("MEDSPRING_PIP_BUILD_DIR", ROOT / "build-pip")).resolve()
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(build), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython3_EXECUTABLE={sys.executable}", "-DMEDSPRING_BUILD_TESTS=OFF", "-DMEDSPRING_BUILD_BENCH=OFF",
            "-DMEDSPRING_BUILD_PYTHON=ON",
        ] + shlex.split(os.environ.get("CMAKE_ARGS", ""))
        subprocess.run(configure, check=True)
        jobs = os.environ.get("JOBS", str(os.cpu_count() or 1))
        subprocess.run(["cmake", "--build", str(build), "--target", ext.target, "--parallel", jobs], check=True)
        built = sorted((build / "python" / "medspring").glob("_medspring*.so"))
        if not built:
            raise RuntimeError(f"CMake did not produce {build}/python/medspring/_medspring*.so")
        dest = Path(self.get_ext_fullpath(ext.name))
        dest.parent.mkdir(parents=True, exist_ok=True)
        self.copy_file(str(built[-1]), str(dest))


setup(
    packages=["medspring", "medspring.study"],
    package_dir={"medspring": "python/medspring"},
    ext_modules=[CMakeExtension("medspring._medspring", target="medspring_python")],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": "build-pip/setuptools"}, "egg_info": {"egg_base": "build-pip"}},
    zip_safe=False,
)
