"""Rigid tools from Python (docs/tools.md): a probe pressing the kidney phantom, its reaction and
contact set as NumPy arrays, and bad input."""

import numpy as np
import pytest

import medspring as ms


def _top(sim):
    S = np.asarray(sim.surface)
    i = int(np.argmax(S[:, 2]))
    return S[i].copy()


def test_probe_press_pushes_back_and_keeps_the_surface_outside():
    sim = ms.Simulation(ms.hybrid_kidney_phantom())
    tools = ms.ToolSimulation(sim)
    top = _top(sim)
    R = 5.0
    k = tools.add_tool(ms.Tool.sphere(R), position=top + [0, 0, R + 1])
    tools.set_path(k, [0.0, 100.0], np.array([top + [0, 0, R + 1], top + [0, 0, R - 3]]))
    assert tools.update(nsteps=1000)
    st = tools.state(k)
    assert st["force"][2] > 0  # the reaction points back up, at the user
    assert st["penetration"] <= 0.05 * R
    c = tools.contacts()
    assert c["point"].shape == (st["contacts"], 3)
    np.testing.assert_allclose(c["bary"].sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(c["normal"], axis=1), 1.0, atol=1e-12)
    d = np.linalg.norm(np.asarray(sim.surface) - st["position"], axis=1)
    assert d.min() >= 0.95 * R
    assert tools.stiffness > 0


def test_bad_tools_and_poses_raise_invalid_input():
    sim = ms.Simulation(ms.hybrid_kidney_phantom())
    tools = ms.ToolSimulation(sim)
    top = _top(sim)
    with pytest.raises(ms.InvalidInput, match="radius"):
        tools.add_tool(ms.Tool.sphere(-1.0), position=top + [0, 0, 9])
    with pytest.raises(ms.InvalidInput, match="position"):
        tools.add_tool(ms.Tool.sphere(1.0), position=[0, np.nan, 0])
    with pytest.raises(ms.InvalidInput, match="starts inside the organ"):
        tools.add_tool(ms.Tool.sphere(1.0), position=np.asarray(sim.surface).mean(axis=0))
    with pytest.raises(ms.InvalidInput):
        ms.Tool.parse("sphere:0")
    assert ms.Tool.parse("grasper:1:10:30").kind == "grasper"
