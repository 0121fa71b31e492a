"""Bad input raises Python exceptions carrying the C++ message; arrays are checked by name and shape."""

import numpy as np
import pytest

import medspring as ms
from conftest import data_file


def test_exception_hierarchy():
    assert issubclass(ms.InvalidInput, ValueError) and issubclass(ms.InvalidInput, ms.Error)
    assert issubclass(ms.IoError, OSError) and issubclass(ms.IoError, ms.Error)
    assert issubclass(ms.SolverError, RuntimeError) and issubclass(ms.SolverError, ms.Error)
    assert ms.InvalidInput.__module__ == "medspring"


@pytest.fixture
def sim():
    return ms.Simulation(ms.hybrid_kidney_phantom())


@pytest.mark.parametrize(
    "value, got",
    [
        (np.zeros((500, 2)), "float64 array of shape (500, 2)"),
        (np.zeros((499, 3)), "float64 array of shape (499, 3)"),
        (np.zeros((500, 3), dtype=np.float32), "float32 array of shape (500, 3)"),
        (np.zeros((500, 3), dtype=np.int64), "int64 array of shape (500, 3)"),
        (np.zeros((3, 500)).T, "non-contiguous float64 array of shape (500, 3)"),
        (np.zeros(1500), "float64 array of shape (1500,)"),
        ("positions", "str"),
    ],
)
def test_wrong_position_arrays_name_the_argument_and_the_expected_shape(sim, value, got):
    with pytest.raises(ValueError) as e:
        sim.positions = value
    assert isinstance(e.value, ms.InvalidInput)
    assert str(e.value) == f"positions: expected a C-contiguous float64 array of shape (500, 3); got a {got}"


def test_nan_positions_are_rejected_naming_the_row(sim):
    x = np.array(sim.positions)
    x[7, 1] = np.nan
    with pytest.raises(ms.InvalidInput, match=r"^positions: expected finite values in .* shape \(500, 3\); row 7 "):
        sim.positions = x
    assert np.isfinite(sim.positions).all()  # unchanged


def test_mesh_constructor_checks_vertices_and_faces():
    V = np.zeros((4, 3))
    with pytest.raises(ms.InvalidInput, match=r"^V: expected a C-contiguous float64 array of shape \(N, 3\)"):
        ms.SurfaceMesh(V[:, :2], [[0, 1, 2]])
    with pytest.raises(ms.InvalidInput, match=r"^F: expected a C-contiguous integer array of shape \(F, 3\)"):
        ms.SurfaceMesh(V, np.array([[0.0, 1.0, 2.0]]))
    with pytest.raises(ms.InvalidInput, match=r"^F\[1\]: index 4 out of range \[0, 4\)"):
        ms.SurfaceMesh(V, [[0, 1, 2], [1, 2, 4]])
    with pytest.raises(ms.InvalidInput, match=r"^V: expected finite values"):
        ms.SurfaceMesh(np.full((4, 3), np.inf), [[0, 1, 2]])


def test_vectors_and_loads_are_checked(sim):
    with pytest.raises(ms.InvalidInput, match=r"^force: expected 3 finite numbers"):
        ms.PointLoad(node=0, force=(0, 1))
    with pytest.raises(ms.InvalidInput, match=r"^force: expected 3 finite numbers .*\(nan, 0, 0\)"):
        ms.PointLoad(node=0, force=(np.nan, 0, 0))
    with pytest.raises(ms.InvalidInput, match=r"loads\[1\]\.node"):
        sim.set_loads([ms.PointLoad(node=0, force=(0, 0, 1)), ms.PointLoad(node=458, force=(0, 0, 1))])
    with pytest.raises(TypeError, match="unknown field 'forse'"):
        ms.PointLoad(node=0, forse=(0, 0, 1))


def test_invalid_settings_raise_with_the_cpp_message():
    with pytest.raises(ms.InvalidInput, match=r"^step\.dt: must be > 0 \(got -1\)$"):
        ms.Simulation(ms.hybrid_kidney_phantom(), ms.SimulationSettings(step=ms.StepSettings(dt=-1)))
    with pytest.raises(ms.InvalidInput, match="integrator: unknown value 'rk4'"):
        ms.StepSettings(integrator="rk4")
    with pytest.raises(ms.InvalidInput, match=r"springs\[0\]\.k: must be >= 0"):
        _negative_spring_model()
    settings = ms.StepSettings()
    with pytest.raises(ms.InvalidInput, match="integrator: unknown value 'rk4'"):
        settings.integrator = "rk4"
    settings.integrator = "implicit"
    assert settings.integrator == ms.Integrator.ImplicitEuler


def _negative_spring_model():
    b = ms.ModelBuilder("bad")
    b.add_node((0, 0, 0))
    b.add_node((1, 0, 0))
    b.add_spring(0, 1, -1.0)
    return b.build()


def test_index_arguments_are_range_checked():
    kidney = ms.hybrid_kidney_phantom()
    with pytest.raises(ms.InvalidInput, match=r"^node: index 458 out of range \[0, 458\)"):
        kidney.transfer_force(458, (0, 0, 1))
    with pytest.raises(ms.InvalidInput, match=r"^atom: index 42 out of range"):
        kidney.atom_dof(42)


def test_soft_spring_overload_raises_solver_error():
    # ALGORITHMS.md §8.1-2: k = 1, k' = -0.01 peaks at 3.849 N; F = 4 has no equilibrium
    b = ms.ModelBuilder("soft")
    b.add_node((0, 0, 0), fixed=True)
    b.add_node((10, 0, 0), return_k=0.0)
    b.add_spring(0, 1, 1.0, -0.01)
    model = b.build()
    f = np.zeros((2, 3))
    f[1, 0] = 3.0
    assert abs(ms.static_equilibrium(model, f).x[1, 0] - 10 - 3.3893624159) < 1e-8
    f[1, 0] = 4.0
    with pytest.raises(ms.SolverError, match="^soft: static solve: no equilibrium found"):
        ms.static_equilibrium(model, f)


def test_missing_file_raises_io_error_naming_the_file(tmp_path):
    missing = tmp_path / "nothing.obj"
    with pytest.raises(OSError) as e:
        ms.read_mesh(missing)
    assert isinstance(e.value, ms.IoError) and str(missing) in str(e.value)
    with pytest.raises(ms.IoError, match="unit|extension|nothing.xyz"):
        ms.read_mesh(tmp_path / "nothing.xyz")


def test_malformed_file_raises_io_error_with_the_cpp_message(tmp_path):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    with pytest.raises(ms.IoError, match="bad.obj"):
        ms.read_mesh(bad)
    with pytest.raises(ms.InvalidInput, match="unknown length unit 'furlong'"):
        ms.read_mesh(data_file("kidney_left_hubmap_vhm.obj"), unit="furlong")
