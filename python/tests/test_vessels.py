"""Vessels that bend like vessels (issue 17, docs/vessels.md): the bending stiffness of the wall, the
paper-literal chain (k_b = 0), and the per-update validity rho kappa < 1 from Python."""

import math

import numpy as np
import pytest

import medspring as ms


def test_wall_bending_stiffness_is_e_i_of_a_hollow_tube_over_h_cubed():
    atoms = np.array([[2.5 * i, 0.0, 0.0] for i in range(5)])
    radius = np.full(5, 4.0)
    kb = ms.wall_bending_stiffness(atoms, radius, ms.WallSettings(E=0.4, thickness_ratio=0.25))
    inertia = math.pi / 4 * (5.0**4 - 4.0**4)
    np.testing.assert_allclose(kb[1:4], 0.4 * inertia / 2.5**3, rtol=1e-14)
    assert kb[0] == 0.0 and kb[4] == 0.0
    with pytest.raises(ms.InvalidInput):
        ms.wall_bending_stiffness(atoms, np.array([4.0, 4.0, -1.0, 4.0, 4.0]))


def test_default_vessel_bends_from_its_wall_and_k_b_zero_is_the_paper_chain():
    wall = ms.smrm_phantom("arc", "circular")
    assert wall.settings.bending == ms.BendingMode.Wall
    assert wall.bending_stiffness[1:-1].min() > 0
    paper = ms.smrm_phantom("arc", "circular", ms.SmrmSettings(bending="constant"))
    assert paper.settings.chain.kb == 0.0
    assert np.all(paper.bending_stiffness == 0.0)
    result = ms.run_vessel_experiment(wall, ms.VesselExperimentSettings(t_end=500.0))
    kinked = ms.run_vessel_experiment(paper, ms.VesselExperimentSettings(t_end=500.0))
    assert result.strong_nonlinear.max_turning_change_deg < kinked.strong_nonlinear.max_turning_change_deg
    assert result.strong_nonlinear.rho_kappa_violations == 0


def test_validity_and_turning_angle_of_a_kinked_chain():
    v = ms.smrm_phantom("straight_x", "circular", ms.SmrmSettings(bending="constant"))
    atoms = np.array(v.rest_atoms)
    h = np.linalg.norm(atoms[1] - atoms[0])
    atoms[21:] = atoms[20] + np.outer(np.arange(1, len(atoms) - 20), [0.0, h, 0.0])
    degrees, atom = v.max_turning_change_deg(atoms)
    assert degrees == pytest.approx(90.0, abs=1e-9) and atom == 20
    check = v.validity(atoms)
    assert check.max_rho_kappa == pytest.approx(v.atom_radius[20] * math.sqrt(2) / h, rel=1e-9)


def test_tree_from_numpy_parent_indices_is_exact_at_rest_and_moves_the_loaded_branch():
    # A Y: trunk 0-1-2-3, branches 3-4-5-6 and 3-7-8-9 (mm).
    atoms = np.array([[0, 0, 0], [5, 0, 0], [10, 0, 0], [15, 0, 0], [20, 3, 0], [25, 6, 0], [30, 9, 0],
                      [20, -3, 0], [25, -6, 0], [30, -9, 0]], float)
    parent = np.array([-1, 0, 1, 2, 3, 4, 5, 3, 7, 8])
    tree = ms.smrm_tree_from_parents(atoms, parent, np.full(10, 1.0), ms.SmrmSettings(atoms=7))
    assert tree.num_branches == 3 and tree.num_junctions == 1
    assert tree.branch_atoms(1)[0] == tree.branch_atoms(0)[-1] == tree.branch_atoms(2)[0]
    sim = ms.Simulation(tree)
    np.testing.assert_allclose(sim.surface, tree.rest_surface, rtol=0, atol=1e-9)
    leaf = tree.branch_atoms(2)
    node = next(k for k in range(tree.num_surface_nodes) if tree.node_atom(k) == leaf[len(leaf) // 2])
    sim.set_loads([ms.PointLoad(node=node, force=[0.0, -0.05, 0.0], t_ramp=20.0)])
    sim.update(nsteps=400)
    u = np.linalg.norm(sim.state.x - tree.model.x0, axis=1)
    assert int(np.argmax(u)) in leaf
    with pytest.raises(ms.InvalidInput, match=r"parent\[2\]: 5 is not -1"):
        ms.smrm_tree_from_parents(atoms[:3], np.array([-1, 0, 5]), np.ones(3))


def test_tree_model_package_round_trip(tmp_path):
    # A Y tree saved as a model package (kind smrm_tree) rebuilds the same tree and surface.
    atoms = np.array([[0, 0, 0], [5, 0, 0], [10, 0, 0], [15, 0, 0], [20, 3, 0], [25, 6, 0], [30, 9, 0],
                      [20, -3, 0], [25, -6, 0], [30, -9, 0]], float)
    parent = np.array([-1, 0, 1, 2, 3, 4, 5, 3, 7, 8])
    tree = ms.smrm_tree_from_parents(atoms, parent, np.full(10, 1.0), ms.SmrmSettings(atoms=7))
    path = str(tmp_path / "y.msm")
    ms.save_model_package(path, tree, "Y tree")
    back = ms.load_model_package(path)
    assert back.kind == "smrm_tree"
    assert back.num_branches == 3 and back.num_junctions == 1
    np.testing.assert_array_equal(back.rest_surface, tree.rest_surface)
    np.testing.assert_array_equal(back.model.x0, tree.model.x0)


# Out of plane and not mirror-symmetric: a planar symmetric Y puts tube vertices of the union exactly on
# each other's edges, and CGAL leaves zero-area triangles (now collapsed; docs/vessels.md).
Y_ATOMS = np.array([[0, 0, 0], [5, 0.3, 0.2], [10, 0.5, -0.2], [15, 0.2, 0.1], [20, 3.3, 1.1], [25, 6.2, 2.3],
                    [30, 9.4, 3.1], [19.6, -3.2, -0.7], [24.1, -6.3, -1.6], [28.7, -9.1, -2.2]], float)
Y_PARENT = np.array([-1, 0, 1, 2, 3, 4, 5, 3, 7, 8])


def closed_manifold_edges(faces):
    # Every undirected edge in exactly two triangles, once in each direction (closed, consistently oriented).
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    undirected = np.sort(directed, axis=1)
    _, counts = np.unique(undirected, axis=0, return_counts=True)
    _, dcounts = np.unique(directed, axis=0, return_counts=True)
    return bool(np.all(counts == 2) and np.all(dcounts == 1))


@pytest.mark.skipif(not ms._medspring.has_builders, reason="built without the builders layer (CGAL)")
def test_blended_tree_from_numpy_is_one_closed_surface_exact_at_rest_and_survives_a_package(tmp_path):
    # blend=True: the union of the Y's closed path tubes is the surface the atoms deform.
    settings = ms.SmrmSettings(atoms=7)
    tubes = ms.smrm_tree_from_parents(Y_ATOMS, Y_PARENT, np.full(10, 1.0), settings)
    tree = ms.smrm_tree_from_parents(Y_ATOMS, Y_PARENT, np.full(10, 1.0), settings, blend=True)
    assert tree.blended and not tubes.blended
    assert tree.num_branches == 3 and tree.num_junctions == 1
    assert closed_manifold_edges(np.asarray(tree.faces))
    assert not closed_manifold_edges(np.asarray(tubes.faces))  # three open tubes
    sim = ms.Simulation(tree)
    np.testing.assert_allclose(sim.surface, tree.rest_surface, rtol=0, atol=1e-9)
    # A press on the middle of branch 2 moves branch 2's atoms most.
    leaf = tree.branch_atoms(2)
    node = next(k for k in range(tree.num_surface_nodes)
                if tree.node_branch(k) == 2 and tree.node_atom(k) == leaf[len(leaf) // 2])
    sim.set_loads([ms.PointLoad(node=node, force=[0.0, -0.05, 0.0], t_ramp=20.0)])
    sim.update(nsteps=400)
    u = np.linalg.norm(sim.state.x - tree.model.x0, axis=1)
    assert int(np.argmax(u)) in leaf
    assert np.all(np.isfinite(sim.surface))
    # The package keeps the blended surface: rebuilt without CGAL, same faces and rest surface.
    path = str(tmp_path / "y_blend.msm")
    ms.save_model_package(path, tree, "Y tree, watertight")
    back = ms.load_model_package(path)
    assert back.kind == "smrm_tree" and back.blended
    np.testing.assert_array_equal(back.faces, tree.faces)
    np.testing.assert_array_equal(back.rest_surface, tree.rest_surface)
    with pytest.raises(ms.InvalidInput, match="blend spacing must be >= 0"):
        ms.smrm_tree_from_parents(Y_ATOMS, Y_PARENT, np.full(10, 1.0), settings, blend=True, blend_spacing=-1.0)


@pytest.mark.skipif(not (ms._medspring.has_builders and ms._medspring.has_scene and ms._medspring.has_io),
                    reason="needs the builders, scene and io layers")
def test_scene_with_a_blended_vmr_tree_runs_on_the_watertight_surface():
    from conftest import data_file

    line = data_file("vmr-0159-aorta-centerline.vtp")
    doc = {"name": "tree", "model": {"kind": "smrm", "source": {"centerline": {
        "file": str(line), "unit": "cm", "branches": "all", "blend": True}}},
        "loads": [{"node": 1900, "direction": "inward_normal", "magnitude": 0.5, "t_ramp": 20}],
        "duration": 60}
    out = ms.run_scene(doc, field_times=[60.0])
    assert out["fields"].shape[1] == 2083  # the union's nodes, not the 7 tubes' 1980
    assert out["summary"]["contact_hold_mm"] > 0.1 and out["summary"]["warnings"] == 0
    assert np.all(np.isfinite(out["fields"]))
    lines = ms.read_centerlines(str(line), "cm")
    tree = ms.smrm_tree_from_centerlines(lines, blend=True)
    assert tree.blended and tree.num_surface_nodes == 2083 and tree.num_atoms == 60
