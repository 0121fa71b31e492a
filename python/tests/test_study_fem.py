"""FEM references and calibration on Dask distributed (medspring.study.fem, docs/studies.md): a local
cluster of 2 worker processes solves the CalculiX cases of a coarse sphere and gives the serial results
bit for bit; the FEM cache is used by the workers; a failing case is recorded, not fatal."""

import os
import shutil

import numpy as np
import pytest

import medspring as ms

pytestmark = pytest.mark.skipif(
    not getattr(ms, "has_fem", False) or shutil.which("ccx") is None or shutil.which("tetgen") is None,
    reason="needs the fem layer, ccx and tetgen")

from medspring.study import fem  # noqa: E402

KW = dict(support_direction=(0, 0, -1), support_depth=3.0, radius=4.0)


def sphere():
    s = ms.icosphere(2, 10.0)  # 162 vertices: a coarse mesh, ~1 s per CalculiX solve
    return np.array(s.V), np.array(s.F)


def set_cache(path):
    os.environ["MEDSPRING_FEM_CACHE"] = path


def cases(V):
    top = V[np.argmax(V[:, 2])]
    side = V[np.argmax(V[:, 0] + V[:, 2])]
    return [
        {"centre": top, "force": (0, 0, -1e-3), "E_kPa": 10.0},
        {"centre": top, "force": (0, 0, -2e-3), "E_kPa": 20.0},
        {"centre": side, "force": (-1e-3, 0, -1e-3), "E_kPa": 10.0, "nu": 0.3},
        {"centre": top, "force": (0, 0, -1e-3), "nu": 0.5},  # a bad material: recorded, not fatal
    ]


@pytest.fixture(scope="module")
def client():
    from medspring.study import local_client

    c, cluster = local_client(2)
    yield c
    c.close()
    cluster.close()


def test_references_on_a_local_cluster_equal_the_serial_ones_and_use_the_cache(client, tmp_path, monkeypatch):
    V, F = sphere()
    monkeypatch.setenv("MEDSPRING_FEM_CACHE", str(tmp_path / "serial"))
    serial = fem.references(V, F, cases(V), workers=0, **KW)
    # The workers read $MEDSPRING_FEM_CACHE when they solve: point them at an empty cache of their own so
    # that they really run CalculiX.
    client.run(set_cache, str(tmp_path / "dist"))
    dist = fem.references(V, F, cases(V), client=client, **KW)
    assert [r["ok"] for r in serial] == [True, True, True, False]
    assert [r["ok"] for r in dist] == [True, True, True, False]
    assert "nu must be" in dist[3]["error"] and dist[3]["displacement"] is None
    for a, b in zip(serial[:3], dist[:3]):
        assert np.array_equal(a["displacement"], b["displacement"])  # bit for bit
    top = int(np.argmax(V[:, 2]))
    u0, u1 = dist[0]["displacement"], dist[1]["displacement"]
    assert u0[top, 2] < 0  # pressed down
    assert u1[top, 2] / u0[top, 2] == pytest.approx(1.0, rel=0.02)  # twice the force on twice the modulus
    # Each solved case left one entry in the workers' cache; solving again hits it (the cached run's
    # wall time comes back unchanged, which a fresh CalculiX run would not reproduce).
    assert len(list((tmp_path / "dist").iterdir())) == 3
    again = fem.references(V, F, cases(V)[:3], client=client, **KW)
    assert [r["solve_seconds"] for r in again] == [r["solve_seconds"] for r in dist[:3]]
    assert all(np.array_equal(a["displacement"], b["displacement"]) for a, b in zip(again, dist))
    with pytest.raises(ms.InvalidInput, match="cases\\[0\\]: unknown key 'E'"):
        fem.references(V, F, [{"centre": V[0], "force": (0, 0, 1), "E": 3}], client=client)


def test_calibration_with_its_solves_on_the_cluster_equals_the_serial_calibration(client, tmp_path, monkeypatch):
    V, F = sphere()
    monkeypatch.setenv("MEDSPRING_FEM_CACHE", str(tmp_path / "serial"))
    client.run(set_cache, str(tmp_path / "dist"))
    atoms = np.array([[-4.0, 0, 0], [0, 0, 0], [4.0, 0, 0]])
    train = np.array([V[np.argmax(V[:, 2])], V[np.argmax(V[:, 0] + V[:, 2])]])
    push = np.tile([0.0, 0.0, -0.02], (2, 1))
    serial = ms.calibrate(V, F, atoms, train, push, E_kPa=10.0, **KW)
    held = [{"centre": V[np.argmax(V[:, 1] + V[:, 2])], "force": (0, 0, -0.02)},
            {"centre": train[0], "force": (0, 0, -0.02), "nu": 0.7}]  # fails: recorded
    dist = fem.calibrate(V, F, atoms, train, push, held_out=held, E_kPa=10.0, client=client, **KW)
    for k in ("k_surf", "k_spoke", "k_cl", "k_r", "k_loc"):
        assert dist["parameters"][k] == serial[k]  # bit for bit: the same references, the same fit
    assert list(dist["parameters"]["support"]) == list(serial["support"])
    assert [t["ok"] for t in dist["training"]] == [True, True]
    ok, bad = dist["held_out"]
    assert ok["ok"] and ok["contact_fem"] > 0
    assert np.isfinite(ok["contact_error"]) and ok["rms_error"] < 1.0
    assert not bad["ok"] and "nu must be" in bad["error"]
    with pytest.raises(ms.InvalidInput, match="fem_displacements has 1 arrays for 2 training loads"):
        ms.calibrate(V, F, atoms, train, push, fem_displacements=[np.zeros_like(V)], **KW)
    with pytest.raises(ms.InvalidInput, match="fem_displacements\\[0\\]"):
        ms.calibrate(V, F, atoms, train, push, fem_displacements=[np.zeros((3, 3)), np.zeros_like(V)], **KW)
