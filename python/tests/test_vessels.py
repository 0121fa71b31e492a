"""Vessels that bend like vessels (issue 17, docs/vessels.md): the bending stiffness of the wall, the
paper-literal chain (k_b = 0), and the per-update validity rho kappa < 1 from Python."""

import json
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


def y_label_volume(h=0.5):
    """A Y of capsules (trunk radius 4 mm, branches 3 mm, out of plane), as the C++ test
    tests/builders/vessel_tree_skeleton_test.cpp: trunk (0,0,0) -> J (30,0,0), J -> B1, J -> B2."""
    a, j = np.array([0.0, 0.0, 0.0]), np.array([30.0, 0.0, 0.0])
    b1, b2 = np.array([55.0, 18.0, 4.0]), np.array([53.0, -17.0, -3.0])
    origin = np.array([-6.0, -24.0, -10.0])
    dims = [int(np.ceil(68.0 / h)), int(np.ceil(48.0 / h)), int(np.ceil(20.0 / h))]
    ii, jj, kk = np.meshgrid(*[np.arange(n) for n in dims], indexing="ij")
    p = origin + h * np.stack([ii, jj, kk], axis=-1)

    def capsule(p, s, e):
        t = np.clip(((p - s) @ (e - s)) / np.dot(e - s, e - s), 0.0, 1.0)
        return np.linalg.norm(p - (s + t[..., None] * (e - s)), axis=-1)

    inside = (capsule(p, a, j) <= 4.0) | (capsule(p, j, b1) <= 3.0) | (capsule(p, j, b2) <= 3.0)
    return ms.LabelVolume(inside.astype(np.int32), spacing=(h, h, h), origin=origin)


@pytest.mark.skipif(not (ms._medspring.has_builders and ms._medspring.has_io),
                    reason="needs the builders layer (CGAL) and the io layer")
def test_tree_from_a_segmentation_is_the_y_watertight_and_on_the_wall(tmp_path):
    # smrm_tree_from_organ = `medspring build vessel --segmentation F --branches all` (its default: the
    # watertight surface marched to the wall, the ends extended to the input's tips)
    path = tmp_path / "y.mha"
    ms.write_label_volume(str(path), y_label_volume())
    settings = ms.SmrmSettings(atoms=16)
    tree, summary, surface = ms.smrm_tree_from_organ(segmentation=path, settings=settings)
    assert summary["branches"] == 3 and summary["junctions"] == 1
    assert tree.blended and summary["blended"] and summary["surface_closed"]
    assert summary["rest_error_mm"] <= 1e-9
    assert 0 < summary["hausdorff_mm"] < 1.0  # measured 0.81 mm (the C++ test's figure; 0.83 before the fit)
    assert summary["mean_distance_mm"] < 0.03  # measured 0.020 mm (0.075 before)
    assert summary["away_hausdorff_mm"] < 0.5  # away from the cut ends: measured 0.30 mm
    assert np.asarray(surface.V).shape[1] == 3
    sim = ms.Simulation(tree)
    np.testing.assert_allclose(sim.surface, tree.rest_surface, rtol=0, atol=1e-9)
    # blend=False: one open tube per branch with the skeleton's circles, farther from the wall
    tubes, plain, _ = ms.smrm_tree_from_organ(segmentation=path, settings=settings, blend=False)
    assert not tubes.blended and not plain["blended"] and plain["branches"] == 3
    assert plain["mean_distance_mm"] > summary["mean_distance_mm"]
    with pytest.raises(ms.InvalidInput, match="exactly one of mesh and segmentation"):
        ms.smrm_tree_from_organ()
    with pytest.raises(ms.InvalidInput, match="label applies to a segmentation"):
        ms.smrm_tree_from_organ(mesh=path, label=1)


def y_mesh():
    """The Y as a closed mesh: the union of its path tubes, 1.5 mm rings (the C++ test's y_mesh)."""
    atoms = np.array([[0, 0, 0], [15, 0, 0], [30, 0, 0], [42.5, 9, 2], [55, 18, 4], [41.5, -8.5, -1.5],
                      [53, -17, -3]], dtype=float)
    radii = np.array([4, 4, 4, 3, 3, 3, 3], dtype=float)
    t = ms.smrm_tree_from_parents(atoms, [-1, 0, 1, 2, 3, 2, 5], radii, ms.SmrmSettings(spokes=24), blend=True,
                                  blend_spacing=1.5)
    return ms.SurfaceMesh(np.ascontiguousarray(t.rest_surface), np.ascontiguousarray(t.faces))


def scene_model(source, atoms):
    """The rest surface of a scene's smrm model ("branches": "all" in `source`), built by the scene loader."""
    doc = {"name": "tree", "model": {"kind": "smrm", "atoms": atoms, "source": source},
           "loads": [{"node": 0, "direction": "inward_normal", "magnitude": 0.1, "t_ramp": 20}], "duration": 10}
    return ms._medspring.SceneRunner().model(json.dumps(doc))


def canonical_surface(V, F):
    """Nodes in lexicographic order of their coordinates, faces renumbered, each starting at its smallest
    node (orientation kept), sorted: equal for two numberings of one surface."""
    V, F = np.asarray(V), np.asarray(F)
    order = np.lexsort(V.T[::-1])
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    G = rank[F]
    shift = np.argmin(G, axis=1)
    G = np.stack([G[np.arange(len(G)), (shift + k) % 3] for k in range(3)], axis=1)
    return V[order], G[np.lexsort(G.T[::-1])]


def assert_same_tree(model, tree):
    # The same surface to 1e-9 mm. The numbering of a few junction nodes of build_vessel's watertight
    # surface varies from call to call within one process (4 nodes of the Y; not yet traced, see
    # docs/vessels.md), so the nodes are compared in coordinate order with the faces renumbered.
    assert model["num_surface_nodes"] == tree.num_surface_nodes
    V1, F1 = canonical_surface(model["rest_surface"], model["faces"])
    V2, F2 = canonical_surface(tree.rest_surface, tree.faces)
    np.testing.assert_allclose(V1, V2, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(F1, F2)


@pytest.mark.skipif(not (ms._medspring.has_builders and ms._medspring.has_io and ms._medspring.has_scene),
                    reason="needs the builders, io and scene layers")
def test_scene_tree_from_a_mask_or_mesh_is_the_build_vessel_tree(tmp_path):
    # A scene's tree from a segmentation or a mesh is `medspring build vessel --branches all`'s
    # (smrm_tree_from_organ): holes filled, skeleton re-centred, watertight surface fitted to the wall by
    # default, and "blend": false the open tubes, as blend=False.
    mask = tmp_path / "y.mha"
    ms.write_label_volume(str(mask), y_label_volume())
    mesh = tmp_path / "y.obj"
    ms.write_mesh(str(mesh), y_mesh())
    settings = ms.SmrmSettings(atoms=16)
    for key, path in (("segmentation", mask), ("mesh", mesh)):
        src = {"file": str(path), "branches": "all", **({"unit": "mm"} if key == "mesh" else {})}
        model = scene_model({key: src}, 16)
        tree, summary, _ = ms.smrm_tree_from_organ(**{key: path}, settings=settings)
        assert tree.blended and summary["branches"] == 3
        assert_same_tree(model, tree)
        assert any("re-centred" in n for n in model["notes"]), model["notes"]
        tubes, _, _ = ms.smrm_tree_from_organ(**{key: path}, settings=settings, blend=False)
        assert not tubes.blended
        assert_same_tree(scene_model({key: dict(src, blend=False)}, 16), tubes)


@pytest.mark.skipif(not (ms._medspring.has_builders and ms._medspring.has_io and ms._medspring.has_scene),
                    reason="needs the builders, io and scene layers")
def test_scene_tree_from_the_real_aorta_mesh_is_the_build_vessel_tree():
    from conftest import data_file

    path = data_file("aorta_totalseg_ct.obj")
    model = scene_model({"mesh": {"file": str(path), "unit": "mm", "branches": "all"}}, 40)
    tree, summary, _ = ms.smrm_tree_from_organ(mesh=path, settings=ms.SmrmSettings(atoms=40))
    assert_same_tree(model, tree)
    assert summary["away_hausdorff_mm"] < 2.0  # the fitted surface: measured 1.69 mm (docs/vessels.md)


@pytest.mark.skipif(not (ms._medspring.has_builders and ms._medspring.has_io),
                    reason="needs the builders layer (CGAL) and the io layer")
def test_tree_from_the_real_aorta_mask_is_one_branch_near_its_wall():
    from conftest import data_file

    tree, summary, _ = ms.smrm_tree_from_organ(segmentation=data_file("aorta_totalseg_mask.nii.gz"), label=1)
    assert summary["branches"] == 1 and summary["junctions"] == 0 and tree.blended
    assert summary["rest_error_mm"] <= 1e-9
    assert summary["length_mm"] > 340  # the ends reach the scan's cuts (cut a radius short: 319 mm)
    # skeleton re-centred, enclosed holes filled, surface fitted to the wall: measured 2.92 / 0.079 mm
    # (before: 11.8 / 0.37 mm); away from the cut ends 2.92 mm, 1 node over 2 mm (2.28 mm)
    assert summary["hausdorff_mm"] < 3.5 and summary["mean_distance_mm"] < 0.1
    assert summary["away_hausdorff_mm"] < 3.5 and summary["away_nodes_over_2mm"] <= 2
