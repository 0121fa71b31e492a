"""The threaded step from Python (docs/performance.md): StepSettings.threads, agreement with one thread,
bit-identical reruns and the one-line error for a bad thread count."""

import math

import numpy as np
import pytest

import medspring as ms


def _tube_model():
    rings, spokes = 150, 120  # 53 880 springs: two threads' worth
    p = ms.SurfaceBodyParams()
    p.fixed = [j for j in range(spokes)] + [(rings - 1) * spokes + j for j in range(spokes)]
    return ms.make_surface_model(ms.tube(rings, spokes, 2.5, 2.5 * spokes / (2 * math.pi)), p, "tube")


@pytest.fixture(scope="module")
def tube():
    return _tube_model()


def _run(model, threads, frames=10):
    settings = ms.StepSettings(threads=threads)
    state = ms.make_state(model)
    load = ms.PointLoad(node=75 * 120 + 30, force=(0, 0, -2.0), t_ramp=0.0)
    ms.step(model, state, settings, loads=[load], nsteps=frames)
    return state


def test_two_threads_agree_with_one_and_rerun_bit_identically(tube):
    if ms.effective_threads(tube, ms.StepSettings(threads=2)) != 2:
        pytest.skip("this build runs one thread")
    one, two, again = _run(tube, 1), _run(tube, 2), _run(tube, 2)
    x1, x2 = np.asarray(one.x), np.asarray(two.x)
    assert np.abs(x1 - np.asarray(tube.x0)).max() > 1e-4
    assert np.abs(x2 - x1).max() <= 1e-12 * np.abs(x1).max()
    assert np.array_equal(np.asarray(again.x), x2)


def test_small_models_run_on_one_thread():
    assert ms.effective_threads(ms.hybrid_kidney_phantom().model, ms.StepSettings(threads=2)) == 1


@pytest.mark.parametrize("bad", [0, -1, 257, 100000])
def test_bad_thread_counts_raise_one_line(bad):
    with pytest.raises(ms.InvalidInput, match=r"^step\.threads: must be an integer in 1\.\.256 \(got -?\d+\)$"):
        ms.Simulation(ms.hybrid_kidney_phantom(), ms.SimulationSettings(step=ms.StepSettings(threads=bad)))
