"""Scenes from Python in-process (medspring.run_scene, the SceneRunner binding): the runs are the engine's
runs bit for bit, models are reused, overrides go by JSON path and bad ones are named."""

import json
import sys
import threading

import numpy as np
import pytest

import medspring as ms
from conftest import REPO, bits

pytestmark = pytest.mark.skipif(not ms._medspring.has_scene, reason="built without the scene layer")

KIDNEY = REPO / "scenes" / "phantom" / "kidney_1.0N_nonlinear.json"


def short_kidney(duration=60.0):
    doc = ms.scene_document(KIDNEY)
    doc["duration"] = duration
    return doc


def test_fields_are_the_simulation_bit_for_bit():
    # The same press through the Simulation binding: the field at 30 ms is surface - rest of the frame
    # that first reaches 30 ms, bit for bit; the summary's hold displacement is that of the load node.
    doc = short_kidney(60.0)
    out = ms.run_scene(doc, field_times=[30.0, 60.0])
    body = ms.hybrid_kidney_phantom()
    sim = ms.Simulation(body)
    node = out["load_node"]
    assert node == 223
    force = out["load_force"]
    assert np.linalg.norm(force) == pytest.approx(1.0, rel=1e-12)
    sim.set_loads([ms.PointLoad(node=node, force=force, t_ramp=20.0, t_release=500.0)])
    sim.update(nsteps=60)  # 30 ms at dt 0.5
    assert out["field_times"][0] == pytest.approx(30.0)
    np.testing.assert_array_equal(bits(out["fields"][0]), bits(sim.surface - body.rest_surface))
    sim.update(nsteps=60)
    np.testing.assert_array_equal(bits(out["fields"][1]), bits(sim.surface - body.rest_surface))
    hold = np.linalg.norm(out["fields"][1][node])
    assert out["summary"]["contact_peak_mm"] >= hold - 1e-12
    assert out["fields"].shape == (2, 458, 3)


def test_model_is_built_once_and_overrides_apply():
    doc = short_kidney(20.0)
    ms.scenes.scene_runner()  # this thread's runner
    a = ms.run_scene(doc, overrides={"loads[0].magnitude": 0.5}, field_times=[20.0])
    b = ms.run_scene(doc, overrides={"loads[0].magnitude": 0.5}, field_times=[20.0])
    assert not b["model_built"]
    np.testing.assert_array_equal(bits(a["fields"]), bits(b["fields"]))  # deterministic reruns
    zero = ms.run_scene(doc, overrides={"loads[0].magnitude": 0.0}, field_times=[20.0])
    assert np.abs(zero["fields"]).max() < 1e-12  # mm: the rest state, to rounding
    # Held for 300 ms, stiffer spokes move the loaded node less under the same force (a new model is
    # built for it).
    hold = {"loads[0].magnitude": 0.5, "duration": 300.0}
    soft = ms.run_scene(doc, overrides=hold, field_times=[300.0])
    stiff = ms.run_scene(doc, overrides=dict(hold, **{"model.parameters.k_spoke": 0.2}), field_times=[300.0])
    assert stiff["model_built"] and not soft["model_built"]
    n = a["load_node"]
    assert np.linalg.norm(stiff["fields"][0][n]) < 0.6 * np.linalg.norm(soft["fields"][0][n])
    # Another load site: the node key replaces the point / ring+spoke keys.
    other = ms.run_scene(doc, overrides={"loads[0].node": 10, "loads[0].direction": [0, 0, -1]})
    assert other["load_node"] == 10
    np.testing.assert_allclose(other["load_force"], [0, 0, -1.0], atol=1e-15)
    assert "fields" not in other or other["fields"].shape[0] == 0


def test_bad_overrides_name_the_path():
    doc = short_kidney(20.0)
    with pytest.raises(ms.InvalidInput, match=r"model\.parameters\.k_srf"):
        ms.run_scene(doc, overrides={"model.parameters.k_srf": 0.1})
    with pytest.raises(ms.InvalidInput, match=r"loads\[3\]"):
        ms.run_scene(doc, overrides={"loads[3].magnitude": 0.1})
    with pytest.raises(ms.InvalidInput, match=r"loads\[0\]\.node"):
        ms.run_scene(doc, overrides={"loads[0].node": 100000})
    with pytest.raises(ms.InvalidInput, match="field_times"):
        ms.run_scene(doc, field_times=[25.0])
    with pytest.raises(ms.InvalidInput, match="magnitude"):
        ms.run_scene(json.dumps(dict(doc, loads=[dict(doc["loads"][0], magnitude=-1)])))


def test_run_releases_the_gil():
    doc = short_kidney(600.0)
    ms.run_scene(doc)  # build the model first
    started, done = threading.Event(), []

    def worker():
        started.set()
        ms.run_scene(doc)
        done.append(True)

    old = sys.getswitchinterval()
    sys.setswitchinterval(100.0)
    try:
        t = threading.Thread(target=worker)
        t.start()
        started.wait()
        ran_while_engine_worked = not done
        t.join()
    finally:
        sys.setswitchinterval(old)
    assert ran_while_engine_worked
