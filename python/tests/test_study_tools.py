"""Tool trajectories as varied study quantities (docs/studies.md, docs/tools.md): the example study
examples/studies/probe_press.json varies where a spherical probe's press ends (depth and position along
the kidney phantom); deeper presses push harder, and a 2-worker local cluster gives the 1-process results
bit for bit."""

import json

import numpy as np
import pytest

import medspring as ms
from conftest import REPO, bits

pytestmark = pytest.mark.skipif(not ms._medspring.has_scene, reason="built without the scene layer")

study = pytest.importorskip("medspring.study")
zarr = pytest.importorskip("zarr")
pytest.importorskip("distributed")

EXAMPLE = REPO / "examples" / "studies" / "probe_press.json"
Z = "tools_0_path_1_position_2"
X = "tools_0_path_1_position_0"


def test_a_study_of_probe_presses_varies_the_tool_trajectory(tmp_path):
    st = study.load_study(str(EXAMPLE))
    assert st.num_runs == 12
    df = study.run(str(EXAMPLE), out=tmp_path / "one", workers=0, progress=False)
    assert len(df) == 12 and not df["failed"].any()
    assert sorted(set(df[Z])) == [21.0, 22.0 + 2.0 / 3.0, 24.0 + 1.0 / 3.0, 26.0]
    assert sorted(set(df[X])) == [-10.0, 0.0, 10.0]
    for x in (-10.0, 0.0, 10.0):
        rows = df[df[X] == x].sort_values(Z, ascending=False)  # deeper and deeper
        force = rows["tool_final_force_N"].to_numpy()
        disp = rows["max_disp_peak_mm"].to_numpy()
        assert force[-1] > 0.05  # the deepest press (7 mm below the start) touches and pushes
        assert np.all(np.diff(force) >= -1e-9) and force[-1] > 2 * max(force[0], 1e-3)
        assert np.all(np.diff(disp) >= -1e-9)
        assert (rows["tool_peak_force_N"] >= rows["tool_final_force_N"] - 1e-12).all()
        # The held tissue stays on the probe's surface: the deepest node inside it is well below 1 mm.
        assert (rows["tool_peak_penetration_mm"] < 1.0).all()
    g = zarr.open_group(str(tmp_path / "one" / "results.zarr"), mode="r")
    u = g["displacement"][:]
    assert u.shape == (12, 1, 458, 3)
    np.testing.assert_allclose(np.linalg.norm(u[:, 0], axis=2).max(axis=1), df["final_max_disp_mm"], rtol=0.05, atol=1e-6)
    two = study.run(str(EXAMPLE), out=tmp_path / "two", workers=2, progress=False, report=False)
    np.testing.assert_array_equal(bits(two["tool_final_force_N"].to_numpy()), bits(df["tool_final_force_N"].to_numpy()))
    np.testing.assert_array_equal(bits(zarr.open_group(str(tmp_path / "two" / "results.zarr"), mode="r")["displacement"][:]),
                                  bits(u))


def test_a_bad_tool_path_is_refused_naming_it(tmp_path):
    doc = json.loads(EXAMPLE.read_text())
    doc["scene"] = str(REPO / "examples" / "tools" / "probe_press_slide.json")
    doc["vary"][0]["path"] = "tools[3].path[1].position[2]"
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(doc))
    with pytest.raises(ms.InvalidInput, match=r"tools\[3\]"):
        study.load_study(str(p))
