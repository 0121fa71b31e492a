"""`medspring study --device cuda`: refused in one line naming the CPU alternative (docs/gpu.md), with
nothing written; no silent fallback to the CPU."""

import pytest

study_main = pytest.importorskip("medspring.study.__main__")


def test_device_cuda_is_refused_naming_the_cpu_alternative(tmp_path, capsys):
    out = tmp_path / "out"
    rc = study_main.main(["does-not-matter.json", "--out", str(out), "--device", "cuda"])
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "--device cuda" in err and "--device cpu" in err
    assert not out.exists()


def test_unknown_device_is_an_argument_error():
    with pytest.raises(SystemExit) as e:
        study_main.main(["s.json", "--out", "o", "--device", "tpu"])
    assert e.value.code == 2


def test_device_cuda_refusal_names_why(tmp_path, capsys):
    gpu = pytest.importorskip("medspring.gpu")
    rc = study_main.main(["s.json", "--out", str(tmp_path / "o"), "--device", "cuda"])
    assert rc == 2
    err = capsys.readouterr().err.strip()
    if not gpu.built():
        assert "no CUDA backend" in err
    elif not gpu.available()[0]:
        assert gpu.available()[1].splitlines()[0] in err  # the device error (no driver, no device, ...)
    else:
        assert "not written yet" in err
