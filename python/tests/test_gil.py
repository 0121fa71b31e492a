"""update / advance / step release the GIL: another Python thread runs while the engine works.

The switch interval is raised so that the worker thread never hands the GIL over by itself: the main
thread can then only run while the worker is inside the engine if the binding released the GIL."""

import sys
import threading

import pytest

import medspring as ms


@pytest.mark.parametrize("call", ["update", "advance", "step"])
def test_engine_calls_release_the_gil(call):
    body = ms.hybrid_kidney_phantom()
    sim = ms.Simulation(body)
    state = ms.make_state(body.model)
    frames = 6000  # a few tenths of a second of engine work
    started, done = threading.Event(), []

    def worker():
        started.set()
        if call == "update":
            sim.update(nsteps=frames)
        elif call == "advance":
            sim.advance(frames)
        else:
            ms.step(body.model, state, nsteps=frames)
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
    assert done == [True]
