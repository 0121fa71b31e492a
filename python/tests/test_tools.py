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


def test_record_gives_every_update_s_contact_data_as_arrays():
    sim = ms.Simulation(ms.hybrid_kidney_phantom())
    tools = ms.ToolSimulation(sim, friction=0.2)
    top = _top(sim)
    R = 5.0
    k = tools.add_tool(ms.Tool.sphere(R), position=top + [0, 0, R + 1])
    tools.set_path(k, [0.0, 50.0, 100.0], np.array([top + [0, 0, R + 1], top + [0, 0, R - 3], top + [4, 0, R - 3]]))
    n = 300
    h = tools.record(n)
    assert h["time"].shape == (n,) and np.all(np.diff(h["time"]) > 0)
    assert h["ok"].dtype == bool and h["ok"].all()
    for key in ("force", "torque", "position", "grasp_force"):
        assert h[key].shape == (n, 1, 3)
    for key in ("area", "penetration", "triangle_penetration", "contacts", "inside", "grasping"):
        assert h[key].shape == (n, 1)
    c, off = h["contact"], h["offsets"]
    m = int(off[-1])
    assert off.shape == (n + 1,) and off[0] == 0 and np.all(np.diff(off) == h["contacts"][:, 0])
    assert m > 0 and h["contacts"][-1, 0] > 0  # pressed and sliding: in contact at the end
    for key, shape in (("point", (m, 3)), ("normal", (m, 3)), ("bary", (m, 3)), ("force", (m, 3)),
                       ("depth", (m,)), ("area", (m,)), ("triangle", (m,)), ("tool", (m,)), ("part", (m,)),
                       ("update", (m,))):
        assert c[key].shape == shape, key
    assert np.all(c["update"] == np.repeat(np.arange(n), np.diff(off)))
    np.testing.assert_allclose(c["bary"].sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(c["normal"], axis=1), 1.0, atol=1e-12)
    assert np.all(c["depth"] > 0) and np.all(c["depth"] <= 2 * R)
    # the contact points lie on their triangles: the barycentric combination of the triangle's nodes is
    # checked on the last update (the surface the contacts were found on is the one before it)
    last = c["update"] == n - 1
    assert np.all(c["triangle"][last] >= 0)
    # the last update's rows are what contacts() gives now
    now = tools.contacts()
    np.testing.assert_array_equal(now["triangle"], c["triangle"][last])
    np.testing.assert_allclose(now["force"], c["force"][last], rtol=0, atol=0)
    # force balance: the reaction on the tool is minus the sum of the contact forces on the tissue plus the
    # augmented-Lagrangian part, and it points back out of the organ, at the user
    assert h["force"][-1, 0, 2] > 0
    np.testing.assert_allclose(h["force"][-1, 0], tools.state(k)["force"], rtol=0, atol=0)


def test_contact_history_round_trips_through_bytes_bit_for_bit():
    def run(resume_at, total):
        sim = ms.Simulation(ms.hybrid_kidney_phantom())
        tools = ms.ToolSimulation(sim, friction=0.2)
        top = _top(sim)
        k = tools.add_tool(ms.Tool.sphere(5.0), position=top + [0, 0, 6])
        tools.set_path(k, [0.0, 50.0, 100.0], np.array([top + [0, 0, 6], top + [0, 0, 2], top + [3, 0, 2]]))
        first = tools.record(resume_at)
        if resume_at == total:
            return first, None
        data, state = tools.save_history(), sim.state.copy()
        sim2 = ms.Simulation(ms.hybrid_kidney_phantom())
        tools2 = ms.ToolSimulation(sim2, friction=0.2)
        k2 = tools2.add_tool(ms.Tool.sphere(5.0), position=top + [0, 0, 6])
        tools2.set_path(k2, [0.0, 50.0, 100.0], np.array([top + [0, 0, 6], top + [0, 0, 2], top + [3, 0, 2]]))
        sim2.set_state(state)
        tools2.restore_history(data)
        return first, tools2.record(total - resume_at)

    whole, _ = run(160, 160)
    first, rest = run(80, 160)
    assert isinstance(ms.ToolSimulation(ms.Simulation(ms.hybrid_kidney_phantom())).save_history(), bytes)
    np.testing.assert_array_equal(whole["force"][80:], rest["force"])
    np.testing.assert_array_equal(whole["contact"]["depth"][whole["offsets"][80]:], rest["contact"]["depth"])
    with pytest.raises(ms.IoError):
        ms.ToolSimulation(ms.Simulation(ms.hybrid_kidney_phantom())).restore_history(b"garbage")


def test_substep_contact_can_be_switched_on():
    sim = ms.Simulation(ms.hybrid_kidney_phantom())
    assert ms.ToolSimulation(sim, substep=True).num_tools == 0
