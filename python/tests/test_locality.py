"""Issue 15: normals computed when read; a large mesh with scattered numbering simulated in locality
order behind SurfaceBody's (and HybridKidney's) map, the user's numbering kept at every interface."""

import numpy as np

import medspring as ms


def test_normals_are_current_when_read():
    sim = ms.Simulation(ms.hybrid_kidney_phantom())
    sim.set_loads([ms.PointLoad(node=223, force=(0, 0, -1), t_ramp=0)])
    held = sim.normals
    for _ in range(3):
        sim.update(nsteps=5)
        expect = ms.vertex_normals(sim.surface, sim.body.faces)
        np.testing.assert_array_equal(sim.normals, expect)
    np.testing.assert_array_equal(held, sim.normals)  # a held view is refreshed by the next read
    off = ms.SimulationSettings(normals=False)
    sim.set_settings(off)
    sim.update()
    assert sim.normals.shape == (0, 3)


def test_large_shuffled_mesh_keeps_the_users_numbering():
    rings, spokes = 160, 128
    t = ms.tube(rings, spokes, 2.5, 2.5 * spokes / (2 * np.pi))
    old_of_new = np.random.default_rng(15).permutation(t.num_vertices)
    new_of_old = np.argsort(old_of_new)
    mesh = ms.SurfaceMesh(np.ascontiguousarray(t.V[old_of_new]), new_of_old[t.F].astype(np.int32))
    body = ms.SurfaceBody(mesh)
    dof = body.dof_of_surface
    assert sorted(dof.tolist()) == list(range(t.num_vertices))
    assert ms.SurfaceBody(t).dof_of_surface.size == 0  # ring-by-ring numbering is kept
    sim = ms.Simulation(body)
    node = int(new_of_old[(rings // 2) * spokes + spokes // 4])
    sim.set_loads([ms.PointLoad(node=node, force=(0, 0, -0.5), t_ramp=0)])
    sim.update(nsteps=10)
    assert int(np.argmax(np.linalg.norm(sim.displacement(), axis=1))) == node
    np.testing.assert_array_equal(sim.surface, sim.positions[dof])
    np.testing.assert_array_equal(body.rest_surface, mesh.V)


def test_large_shuffled_hybrid_keeps_the_users_numbering():
    rings, spokes = 160, 128
    t = ms.tube(rings, spokes, 2.5, 2.5 * spokes / (2 * np.pi))
    old_of_new = np.random.default_rng(16).permutation(t.num_vertices)
    new_of_old = np.argsort(old_of_new)
    mesh = ms.SurfaceMesh(np.ascontiguousarray(t.V[old_of_new]), new_of_old[t.F].astype(np.int32))
    atoms = np.zeros((30, 3))
    atoms[:, 0] = 2.5 * (rings - 1) * (np.arange(30) + 0.5) / 30  # on the tube's axis
    body = ms.HybridKidney(mesh, atoms)
    dof = body.dof_of_surface
    assert sorted(dof.tolist()) == list(range(t.num_vertices))
    assert ms.HybridKidney(t, atoms).dof_of_surface.size == 0  # ring-by-ring numbering is kept
    assert body.atom_dof(0) == t.num_vertices  # atoms follow the surface nodes
    sim = ms.Simulation(body)
    node = int(new_of_old[(rings // 2) * spokes + spokes // 4])
    sim.set_loads([ms.PointLoad(node=node, force=(0, 0, -0.5), t_ramp=0)])
    sim.update(nsteps=10)
    assert int(np.argmax(np.linalg.norm(sim.displacement(), axis=1))) == node
    np.testing.assert_array_equal(sim.surface, sim.positions[dof])
    np.testing.assert_array_equal(body.rest_surface, mesh.V)
