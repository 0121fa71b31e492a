"""Shapes, dtypes and zero-copy views."""

import gc

import numpy as np
import pytest

import medspring as ms


@pytest.fixture
def kidney_sim():
    return ms.Simulation(ms.hybrid_kidney_phantom())


def test_mesh_arrays_have_engine_shapes_and_dtypes():
    mesh = ms.kidney_phantom()
    assert mesh.V.shape == (458, 3) and mesh.V.dtype == np.float64
    assert mesh.F.shape == (912, 3) and mesh.F.dtype == np.int32
    assert not mesh.V.flags.writeable and not mesh.F.flags.writeable
    assert ms.unique_edges(mesh.F).shape == (1368, 2)
    assert ms.vertex_normals(mesh).shape == (458, 3)
    assert ms.face_normals(mesh.V, mesh.F).shape == (912, 3)
    assert ms.bounds(mesh.V).shape == (2, 3)
    assert ms.tube().V.shape == (1200, 3)


def test_simulation_arrays_have_engine_shapes_and_dtypes(kidney_sim):
    sim = kidney_sim
    assert sim.positions.shape == (500, 3) and sim.positions.dtype == np.float64
    assert sim.velocities.shape == (500, 3) and sim.velocities.dtype == np.float64
    assert sim.surface.shape == (458, 3) and sim.surface.dtype == np.float64
    assert sim.normals.shape == (458, 3)
    assert sim.displacement().shape == (458, 3)
    assert sim.applied_force().shape == (3,)
    assert sim.positions.flags.c_contiguous and sim.positions.flags.writeable
    assert not sim.surface.flags.writeable
    m = sim.model
    assert m.x0.shape == (500, 3) and m.mass.shape == (500,) and m.fixed.dtype == np.bool_
    assert m.springs.i.dtype == np.int32 and m.springs.k.shape == (m.num_springs,)
    assert sim.body.spokes.shape[1] == 2


def test_position_and_velocity_views_share_the_state_memory(kidney_sim):
    sim = kidney_sim
    assert np.shares_memory(sim.positions, sim.state.x)
    assert np.shares_memory(sim.velocities, sim.state.v)
    assert sim.positions.__array_interface__["data"][0] == sim.state.x.__array_interface__["data"][0]


def test_writing_through_the_position_view_changes_the_state(kidney_sim):
    sim = kidney_sim
    body = sim.body
    x = sim.positions
    x[10] += (0.0, 0.0, 2.0)
    # the C++ side sees it: the forward map reads state.x
    np.testing.assert_allclose(body.map_to_surface(sim.state)[10], body.rest_surface[10] + (0, 0, 2.0))
    # and the dynamics respond: the displaced node is pulled back
    sim.update()
    assert sim.velocities[10, 2] < 0


def test_writing_through_the_velocity_view_changes_the_state(kidney_sim):
    sim = kidney_sim
    sim.velocities[5] = (0.0, 1.0, 0.0)
    sim.update()  # at rest no spring acts: v' = m v / (m + h d) = 0.3 / (0.3 + 0.5 * 0.15) = 0.8 mm/ms
    assert sim.positions[5, 1] - sim.model.x0[5, 1] == pytest.approx(0.5 * 0.8, rel=1e-12)


def test_views_stay_valid_across_reset_and_set_state(kidney_sim):
    sim = kidney_sim
    x = sim.positions
    sim.set_loads([ms.PointLoad(node=3, force=(0, 0, 1))])
    sim.update(40)
    checkpoint = sim.state.copy()
    moved = x.copy()
    sim.reset()
    assert sim.time == 0 and np.array_equal(x, sim.model.x0)
    sim.set_state(checkpoint)
    assert np.array_equal(x, moved) and np.shares_memory(x, sim.state.x)


def test_a_view_keeps_its_owner_alive():
    sim = ms.Simulation(ms.hybrid_kidney_phantom())
    sim.update(4)
    x = sim.positions
    s = sim.surface
    expected_x, expected_s = x.copy(), s.copy()
    del sim
    gc.collect()
    assert np.array_equal(x, expected_x) and np.array_equal(s, expected_s)
    mesh_v = ms.kidney_phantom().V  # the temporary mesh lives as long as the view
    gc.collect()
    assert mesh_v.shape == (458, 3) and np.isfinite(mesh_v).all()


def test_surface_view_is_refreshed_in_place_by_update(kidney_sim):
    sim = kidney_sim
    s = sim.surface
    sim.set_loads([ms.PointLoad(node=223, force=(0, 0, -1))])
    sim.update(100)
    assert np.shares_memory(s, sim.surface)
    assert np.linalg.norm(s[223] - sim.body.rest_surface[223]) > 0.5


def test_state_assignment_copies_into_the_same_buffer():
    model = ms.SurfaceBody(ms.icosphere(1)).model
    state = ms.make_state(model)
    view = state.x
    state.x = model.x0 + 1.0
    assert np.shares_memory(view, state.x) and np.allclose(view, model.x0 + 1.0)


def test_state_copy_is_a_checkpoint_not_a_view():
    model = ms.SurfaceBody(ms.icosphere(1)).model
    state = ms.make_state(model)
    copy = state.copy()
    state.x[0] += 1.0
    assert not np.shares_memory(copy.x, state.x) and np.array_equal(copy.x, model.x0)


def test_step_advances_a_standalone_state_in_place():
    model = ms.SurfaceBody(ms.kidney_phantom()).model
    state = ms.make_state(model)
    x = state.x
    state.f_ext[0] = (0, 0, 0.5)
    status = ms.step(model, state, nsteps=10)
    assert status.ok and state.frames == 10 and abs(state.t - 5.0) < 1e-12
    assert x[0, 2] > model.x0[0, 2]


def test_tangent_stiffness_is_a_symmetric_scipy_sparse_matrix():
    model = ms.SurfaceBody(ms.kidney_phantom()).model
    K = ms.tangent_stiffness(model, model.x0)
    assert K.shape == (3 * 458, 3 * 458)
    assert abs(K - K.T).max() < 1e-12


def test_vectorised_spring_law_matches_eq_5():
    delta = np.linspace(-2, 2, 9)
    np.testing.assert_allclose(ms.spring_tension(1.0, 0.01, delta), delta + 0.01 * delta**3, rtol=1e-15)


def test_tool_force_acts_like_a_held_load():
    sim = ms.Simulation(ms.hybrid_kidney_phantom())
    sim.set_tool_force(223, (0.0, 0.0, -0.5))
    assert sim.tool_node == 223 and np.array_equal(sim.tool_force, [0.0, 0.0, -0.5])
    sim.update(200)
    np.testing.assert_allclose(sim.applied_force(), [0.0, 0.0, -0.5])
    assert sim.surface[223, 2] < sim.body.rest_surface[223, 2] - 0.5
    sim.clear_tool_force()
    assert sim.tool_node == -1
    with pytest.raises(ms.InvalidInput):
        sim.set_tool_force(458, (0, 0, 1))
