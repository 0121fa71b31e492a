"""The examples in examples/python run, and the calibration example recovers its parameters."""

import importlib.util

import numpy as np
import pytest

import medspring as ms
from conftest import REPO, data_file


def load_example(name: str):
    path = REPO / "examples" / "python" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"example_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_fitting_example_recovers_k_and_kp_within_2_percent():
    fit = load_example("fit_spring_parameters")
    result = fit.run()  # k = 0.2 N/mm, k' = 0.032 N/mm^3, 40 force levels, 0.3 % noise, seed 0
    k, kp = result["recovered"]
    assert abs(k / 0.2 - 1) < 0.02, result["recovered"]
    assert abs(kp / 0.032 - 1) < 0.02, result["recovered"]
    # the noise-free curve is matched exactly by the true parameters (the fit is not a tautology)
    exact = fit.tensile_curve(fit.strip_model(0.2, 0.032), result["forces"])
    assert np.max(np.abs(result["measured"] / exact - 1)) > 1e-3


def test_fitting_example_writes_its_figure(tmp_path, capsys):
    fit = load_example("fit_spring_parameters")
    assert fit.main(["--out", str(tmp_path)]) == 0
    assert (tmp_path / "fit_spring_parameters.png").stat().st_size > 10_000
    assert "k'" in capsys.readouterr().out


def test_strip_model_reproduces_the_series_chain_reference_of_section_8_1_3():
    # §8.1-3: 10 springs L0 = 1, k = 1, k' = 0.01, F = 1 N -> total elongation 9.902885241
    fit = load_example("fit_spring_parameters")
    model = fit.strip_model(1.0, 0.01, springs=10, rest_length=1.0)
    u = fit.tensile_curve(model, np.array([1.0]))
    assert u[0] == pytest.approx(9.902885241, rel=1e-9)


def test_poke_example_nonlinear_springs_are_stiffer_under_a_strong_poke():
    poke = load_example("poke_kidney")
    mesh = ms.kidney_phantom()  # the real kidney takes ~1 s per static solve; the phantom is quick
    bodies = poke.kidney_bodies(mesh)
    node, direction = poke.poke_node(mesh)
    curves = poke.force_displacement(bodies, node, direction, [0.2, 1.0])
    assert curves["nonlinear"][1] < curves["linear"][1]
    assert np.all(np.diff(curves["linear"]) > 0)


def test_poke_example_runs_on_the_real_kidney_mesh():
    poke = load_example("poke_kidney")
    mesh = ms.read_mesh(data_file(poke.KIDNEY), unit="m")
    assert mesh.num_vertices == 5002 and mesh.num_faces == 10000
    bodies = poke.kidney_bodies(mesh)
    node, direction = poke.poke_node(mesh)
    runs = poke.press(bodies, node, direction, force=1.0, t_end=100.0)
    for run in runs.values():
        assert run["contact"][-1] > 1.0 and run["sim"].state.warnings.total() == 0


def test_aorta_example_bends_the_real_centerline_model():
    bend = load_example("bend_aorta")
    vessel = bend.aorta_vessel(data_file(bend.CENTERLINE))
    assert vessel.num_atoms == 40 and vessel.num_surface_nodes == 1200
    assert vessel.report.curvature.ok
    result = bend.experiment(vessel, t_end=600.0)
    # the wall's bending stiffness (default): a smooth arc, no overlapping cross-sections (issue 17)
    assert result.strong_nonlinear.atom_hold > 4 * result.light_nonlinear.atom_hold > 0.4
    assert result.strong_nonlinear.max_turning_change_deg <= 25.0
    assert result.strong_nonlinear.rho_kappa_violations == 0
    assert result.strong_nonlinear.atom_hold < result.strong_linear.atom_hold  # hard Duffing springs
    sim = bend.bend_with_local_overlay(vessel, result.atom, -result.direction, t_hold=100.0)
    assert len(sim.local_nodes) == 25 and np.abs(sim.local_displacement).max() > 0
