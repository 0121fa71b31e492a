"""The FEM reference from NumPy (docs/accuracy.md): medspring.fem_reference, spring_displacement and
calibrate; needs ccx and tetgen (Debian calculix-ccx, tetgen)."""

import shutil

import numpy as np
import pytest

import medspring as ms

pytestmark = pytest.mark.skipif(
    not getattr(ms, "has_fem", False) or shutil.which("ccx") is None or shutil.which("tetgen") is None,
    reason="needs the fem layer, ccx and tetgen")


def test_fem_reference_of_a_sphere_scales_with_the_modulus_and_refuses_bad_input(tmp_path, monkeypatch):
    monkeypatch.setenv("MEDSPRING_FEM_CACHE", str(tmp_path))
    s = ms.icosphere(2, 10.0)
    V, F = np.array(s.V), np.array(s.F)
    top = V[np.argmax(V[:, 2])]
    kw = dict(support_direction=(0, 0, -1), support_depth=3.0, radius=4.0)
    a = ms.fem_reference(V, F, top, (0, 0, -1e-3), E_kPa=10, **kw)
    b = ms.fem_reference(V, F, top, (0, 0, -1e-3), E_kPa=20, **kw)
    ua, ub = a["displacement"], b["displacement"]
    assert ua.shape == V.shape and a["fem_nodes"] > V.shape[0]
    i = int(np.argmax(V[:, 2]))
    assert ua[i, 2] < 0  # pressed down
    assert ub[i, 2] / ua[i, 2] == pytest.approx(0.5, rel=0.02)  # small strain: linear in 1/E
    with pytest.raises(ms.InvalidInput, match="nu must be"):
        ms.fem_reference(V, F, top, (0, 0, -1e-3), nu=0.5, **kw)
    with pytest.raises(ms.InvalidInput, match="boundary"):
        ms.fem_reference(V, F[:-1], top, (0, 0, -1e-3), **kw)  # open surface


def test_example_fits_the_kidney_phantom_and_reports_held_out_errors():
    import importlib.util
    from conftest import REPO

    path = REPO / "examples" / "python" / "fit_kidney_to_tissue.py"
    spec = importlib.util.spec_from_file_location("fit_kidney_to_tissue", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    r = mod.run(10.0)
    assert all(r["parameters"][k] > 0 for k in ("k_surf", "k_spoke", "k_cl", "k_r"))
    for row in r["held_out"]:
        assert row["contact_fem"] > 0
        assert np.isfinite(row["contact_error"]) and np.isfinite(row["rms_error"])
        assert row["rms_error"] < 0.5  # measured ~0.1; a broken fit or mapping is far above
