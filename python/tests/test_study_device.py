"""`medspring study --device cuda|cpu-batch` (docs/gpu.md, "Study runs on the GPU"): each task's runs
stepped together by a batch engine. Without a GPU (or a CUDA build) --device cuda is refused in one line
naming the cause and --device cpu, with nothing written (no silent fallback). The batch path itself is
checked here on the CPU reference stepper (cpu-batch: bit for bit the scene runs' records); the GPU
comparison (cuda = cpu within tolerance) skips without a device."""

import json

import numpy as np
import pytest

import medspring as ms
from conftest import REPO, bits

study_main = pytest.importorskip("medspring.study.__main__")
needs_scene = pytest.mark.skipif(not ms._medspring.has_scene, reason="built without the scene layer")

KIDNEY = str(REPO / "scenes" / "phantom" / "kidney_1.0N_nonlinear.json")
METRICS = ["contact_peak_mm", "contact_hold_mm", "max_disp_peak_mm", "atom_hold_mm", "return_ms",
           "final_max_disp_mm", "warnings", "substeps"]


def small_study(duration=80.0):
    """2 stiffnesses (two models, one batch) x 2 forces x 2 random nodes, release at 40 ms."""
    return {
        "name": "device_small",
        "scene": KIDNEY,
        "set": {"duration": duration, "loads[0].direction": "inward_normal", "loads[0].t_release": 40},
        "vary": [
            {"path": "model.parameters.k_surf", "values": [0.05, 0.08]},
            {"path": "loads[0].magnitude", "values": [0.4, 1.0]},
            {"path": "loads[0].node", "surface_node": "random"},
        ],
        "samples": {"count": 2},
        "seed": 3,
        "outputs": {"metrics": METRICS, "fields": {"times": [30.0, duration]}},
        "batch": 8,
    }


def gpu_reason():
    try:
        from medspring import gpu
    except ImportError as e:
        return str(e)
    if not gpu.built():
        return "this build has no CUDA backend"
    ok, why = gpu.available()
    return "" if ok else why


def test_device_cuda_without_a_gpu_is_refused_naming_the_cause(tmp_path, capsys):
    if not gpu_reason():
        pytest.skip("a GPU is present: --device cuda runs")
    out = tmp_path / "out"
    rc = study_main.main(["does-not-matter.json", "--out", str(out), "--device", "cuda"])
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "--device cuda" in err and "--device cpu" in err
    from medspring import gpu

    if not gpu.built():
        assert "no CUDA backend" in err
    else:
        cause = gpu.available()[1].splitlines()[0].split("; use the CPU engine")[0]  # the device error
        assert cause in err  # (no driver, no device, ...), without the engine's --gpu hint
    assert not out.exists()


def test_unknown_device_is_an_argument_error():
    with pytest.raises(SystemExit) as e:
        study_main.main(["s.json", "--out", "o", "--device", "tpu"])
    assert e.value.code == 2
    with pytest.raises(ms.InvalidInput, match="device"):
        ms.study.run(small_study(), out="never", device="tpu")


@needs_scene
def test_run_batch_on_the_cpu_reference_equals_the_scene_runs_bit_for_bit():
    """The batch engine's setup (each run's model, loads per frame, traces, summary, fields) against the
    scene runner, on the CPU reference stepper: what the GPU batch receives is what the CPU runs use."""
    base = ms.scene_document(KIDNEY)
    base = ms.scenes.without_key_times(base)
    docs = []
    for k_surf, node, mag, dt in [(0.05, 223, 1.0, 0.5), (0.08, 17, 0.5, 0.5), (0.05, 40, 0.8, 0.25)]:
        d = ms.scenes.apply_overrides(base, {"duration": 60.0, "model.parameters.k_surf": k_surf,
                                             "loads[0].node": node, "loads[0].magnitude": mag,
                                             "loads[0].t_release": 30.0, "integrator.dt": dt})
        docs.append(json.dumps(d))
    bad = {"model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
           "loads": [{"node": 99999, "magnitude": 1, "direction": "inward_normal"}]}
    docs.append(json.dumps(bad))  # fails to build: its error comes back in its place
    runner = ms._medspring.SceneRunner()
    times = [20.0, 60.0]
    out = runner.run_batch(docs, "/", times, True, "cpu", ["a", "b", "c", "bad"])
    assert isinstance(out[3], str) and out[3].startswith("InvalidInput: bad") and "99999" in out[3]
    for text, got in zip(docs[:3], out[:3]):
        ref = ms._medspring.SceneRunner().run(text, "/", "ref", times, True)
        for m in METRICS:
            assert bits(np.float64(got["summary"][m])) == bits(np.float64(ref["summary"][m])), m
        assert got["load_node"] == ref["load_node"]
        np.testing.assert_array_equal(got["load_force"], ref["load_force"])
        np.testing.assert_array_equal(got["field_times"], ref["field_times"])
        np.testing.assert_array_equal(bits(got["fields"]), bits(ref["fields"]))
        assert got["summary"]["contact_peak_mm"] > 0.1


@needs_scene
def test_run_batch_refuses_local_deformation_and_an_unknown_device():
    local = json.dumps({"model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
                        "loads": [{"node": 3, "magnitude": 0.5, "direction": "inward_normal"}],
                        "duration": 5, "local": True})
    with pytest.raises(ms.InvalidInput, match="local deformation overlay"):
        ms._medspring.SceneRunner().run_batch([local], "/", [], False, "cpu")
    with pytest.raises(ms.InvalidInput, match="device"):
        ms._medspring.SceneRunner().run_batch([local], "/", [], False, "tpu")


def study_results(out):
    zarr = pytest.importorskip("zarr")
    from pathlib import Path

    g = zarr.open_group(str(Path(out) / "results.zarr"), mode="r")
    return {k: g[k][:] for k in ["done", "failed", "load_node", "displacement"] + METRICS}


@needs_scene
def test_study_cpu_batch_equals_the_cpu_study(tmp_path):
    pytest.importorskip("zarr")
    spec = tmp_path / "s.json"
    spec.write_text(json.dumps(small_study()))
    a, b = tmp_path / "cpu", tmp_path / "batch"
    assert study_main.main([str(spec), "--out", str(a), "--workers", "0", "--quiet", "--no-report"]) == 0
    assert study_main.main([str(spec), "--out", str(b), "--workers", "0", "--quiet", "--no-report",
                            "--device", "cpu-batch"]) == 0
    ra, rb = study_results(a), study_results(b)
    assert ra["done"].all() and not ra["failed"].any() and not rb["failed"].any()
    for k in ["load_node", "displacement"] + METRICS:
        np.testing.assert_array_equal(bits(ra[k]), bits(rb[k]), err_msg=k)


@needs_scene
def test_study_on_the_gpu_matches_the_cpu_study(tmp_path):
    why = gpu_reason()
    if why:
        pytest.skip(f"GPU: {why.splitlines()[0]}")
    pytest.importorskip("zarr")  # the study writes results.zarr (the device machine has no zarr)
    spec = tmp_path / "s.json"
    spec.write_text(json.dumps(small_study(duration=200.0)))
    a, b = tmp_path / "cpu", tmp_path / "cuda"
    assert study_main.main([str(spec), "--out", str(a), "--workers", "0", "--quiet", "--no-report"]) == 0
    assert study_main.main([str(spec), "--out", str(b), "--quiet", "--no-report", "--device", "cuda"]) == 0
    ra, rb = study_results(a), study_results(b)
    assert not rb["failed"].any()
    np.testing.assert_array_equal(ra["load_node"], rb["load_node"])
    np.testing.assert_array_equal(ra["substeps"], rb["substeps"])
    for k in ["contact_peak_mm", "contact_hold_mm", "max_disp_peak_mm", "atom_hold_mm", "final_max_disp_mm"]:
        np.testing.assert_allclose(rb[k], ra[k], rtol=1e-9, atol=1e-12, err_msg=k)
    np.testing.assert_allclose(rb["displacement"], ra["displacement"], rtol=0, atol=1e-9)


@needs_scene
def test_run_batch_on_cuda_without_a_gpu_raises_the_cause():
    """SceneRunner.run_batch(device="cuda") where no GPU answers: the engine's error (gpu.GpuError, a
    medspring.Error) or, in a build without the backend, an Error naming it; never a CPU run."""
    if not gpu_reason():
        pytest.skip("a GPU is present")
    text = json.dumps({"model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
                       "loads": [{"node": 3, "magnitude": 0.5, "direction": "inward_normal"}], "duration": 5})
    with pytest.raises(ms.Error) as e:
        ms._medspring.SceneRunner().run_batch([text], "/", [], False, "cuda")
    msg = str(e.value)
    assert "no CUDA backend" in msg or "CPU engine" in msg, msg


@needs_scene
def test_device_auto_says_which_engine_and_why(tmp_path, capsys):
    pytest.importorskip("zarr")
    spec = tmp_path / "s.json"
    spec.write_text(json.dumps(small_study(duration=40.0)))
    rc = study_main.main([str(spec), "--out", str(tmp_path / "o"), "--workers", "0", "--quiet", "--no-report",
                          "--device", "auto"])
    assert rc == 0
    err = capsys.readouterr().err
    why = gpu_reason()
    if why:
        assert "--device auto: the CPU engine (" in err and why.splitlines()[0] in err
    else:
        assert "--device auto: the GPU engine" in err
