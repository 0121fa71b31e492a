"""The compiled module exports its init function and nothing else (python/module.map, issue 21). The
static engine layers are built with default visibility; exported, their weak copies of standard-library
code (C++20 emits constexpr std::string members and inline facet members such as ctype<char>::do_widen
in every translation unit) are bound by libstdc++.so itself, whose own calls -- formatting a double into
an ostringstream at module init -- then run the module's copies."""

import shutil
import subprocess

import pytest

import medspring as ms

NM = shutil.which("nm")


@pytest.mark.skipif(NM is None, reason="binutils' nm is not installed")
def test_the_module_exports_only_its_init_function():
    path = ms._medspring.__file__
    out = subprocess.run([NM, "-D", "--defined-only", path], capture_output=True, text=True, check=True).stdout
    names = sorted(line.split()[-1] for line in out.splitlines() if line.strip())
    assert names == ["PyInit__medspring"], f"{path} exports {len(names)} symbols, e.g. {names[:5]}"
