"""Checkpoints and model packages from Python: bit-identical resume, exact rebuild, clean refusals."""

import numpy as np
import pytest

import medspring as ms


def pressed(body):
    sim = ms.Simulation(body)
    sim.set_loads([ms.PointLoad(node=223, force=(0, 0, -1), t_ramp=20, t_release=60)])
    return sim


def test_resuming_a_checkpoint_is_bit_identical(tmp_path):
    a = pressed(ms.hybrid_kidney_phantom())
    for _ in range(50):
        a.update()
    path = tmp_path / "run.mscp"
    a.save_checkpoint(str(path))
    b = pressed(ms.hybrid_kidney_phantom())
    x = b.positions  # a view taken before the restore stays valid
    b.restore_checkpoint(str(path))
    assert b.time == a.time
    for _ in range(150):
        a.update()
        b.update()
    assert np.array_equal(a.positions, b.positions)
    assert np.shares_memory(x, b.positions) and np.array_equal(x, a.positions)


def test_a_corrupted_or_foreign_checkpoint_is_refused(tmp_path):
    a = pressed(ms.hybrid_kidney_phantom())
    a.update()
    path = tmp_path / "run.mscp"
    a.save_checkpoint(str(path))
    data = bytearray(path.read_bytes())
    data[-5] ^= 0xFF
    bad = tmp_path / "bad.mscp"
    bad.write_bytes(bytes(data))
    with pytest.raises(ms.IoError, match="corrupted checkpoint"):
        a.restore_checkpoint(str(bad))
    tube = ms.Simulation(ms.SurfaceBody(ms.tube(8, 10), ms.SurfaceBodyParams()))
    with pytest.raises(ms.InvalidInput, match="saved from another model"):
        tube.restore_checkpoint(str(path))


def test_model_package_rebuilds_the_body_exactly(tmp_path):
    body = ms.hybrid_kidney_phantom()
    path = tmp_path / "kidney.msm"
    ms.save_model_package(str(path), body, "kidney", "phantom")
    again = ms.load_model_package(str(path))
    assert again.kind == "hybrid"
    assert np.array_equal(again.rest_surface, body.rest_surface)
    a, b = pressed(body), pressed(again)
    for _ in range(100):
        a.update()
        b.update()
    assert np.array_equal(a.positions, b.positions)
    path.write_bytes(path.read_bytes()[:100])
    with pytest.raises(ms.IoError, match="truncated model package"):
        ms.load_model_package(str(path))
