"""Tissue materials from Python: medspring.tissue_settings (a preset or {E_kPa, nu} -> the calibrated
settings of a model kind) and the scene "material" block through run_scene (docs/accuracy.md)."""

import numpy as np
import pytest

import medspring as ms
from conftest import REPO


def test_presets_give_the_calibrated_stiffnesses():
    s = ms.tissue_settings("kidney")  # hybrid, Duffing, phantom calibration at 10 kPa, nu 0.45
    # `medspring calibrate --organ phantom --E-kPa 10 --nu 0.45` (docs/accuracy.md)
    assert s.k_surf == pytest.approx(0.0118, abs=5e-5)
    assert s.k_cl == pytest.approx(9.14, abs=5e-3)
    assert s.surface_node.return_k == pytest.approx(0.0221, abs=5e-5)
    twice = ms.tissue_settings({"E_kPa": 20.0, "nu": 0.45})
    assert twice.k_surf / s.k_surf == pytest.approx(2.0, rel=1e-12)
    assert twice.k_spoke / s.k_spoke == pytest.approx(2.0, rel=1e-12)
    assert ms.tissue_settings("aorta", kind="smrm").wall.E == pytest.approx(0.065)
    surface = ms.tissue_settings({"preset": "kidney"}, kind="surface", organ="kidney")
    assert surface.k > 1.0  # the plain surface model needs springs ~10^3 stiffer than the default 0.05


def test_bad_materials_are_refused_naming_the_key():
    with pytest.raises(ms.InvalidInput, match=r"material\.nu"):
        ms.tissue_settings({"E_kPa": 10.0, "nu": 0.5})
    with pytest.raises(ms.InvalidInput, match=r"material\.E_kPa"):
        ms.tissue_settings({"E_kPa": 0.0})
    with pytest.raises(ms.InvalidInput, match=r"material\.E_kPa: is required"):
        ms.tissue_settings({"nu": 0.3})
    with pytest.raises(ms.InvalidInput, match="kidney, aorta"):
        ms.tissue_settings("liver")
    with pytest.raises(ms.InvalidInput, match=r"material\.G"):
        ms.tissue_settings({"E_kPa": 10.0, "G": 1.0})


@pytest.mark.skipif(not ms._medspring.has_scene, reason="built without the scene layer")
def test_scene_material_stiffer_tissue_moves_less():
    doc = ms.scene_document(REPO / "scenes" / "phantom" / "kidney_1.0N_nonlinear.json")
    doc["duration"] = 300.0
    # scene_document fills in every default, "parameters" included, and explicit parameters override the
    # material: drop them so that the material decides the stiffnesses.
    doc["model"] = {k: v for k, v in doc["model"].items() if k != "parameters"}
    doc["model"]["nonlinear"] = False  # linear springs: the static displacement scales as 1 / E exactly
    hold = {"loads[0].magnitude": 0.2}
    soft = ms.run_scene(dict(doc, model=dict(doc["model"], material="kidney")), overrides=hold, field_times=[300.0])
    hard = ms.run_scene(dict(doc, model=dict(doc["model"], material={"E_kPa": 20.0})), overrides=hold,
                        field_times=[300.0])
    n = soft["load_node"]
    ratio = np.linalg.norm(hard["fields"][0][n]) / np.linalg.norm(soft["fields"][0][n])
    assert 0.45 < ratio < 0.56  # 0.506 measured: ~1/2 once settled (mass and damping are not scaled)
    with pytest.raises(ms.InvalidInput, match=r"model\.material\.nu"):
        ms.run_scene(dict(doc, model=dict(doc["model"], material={"E_kPa": 10.0, "nu": 0.6})))
