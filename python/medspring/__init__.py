"""MedSpring: real-time soft-tissue simulation for NumPy.

Surface mass-spring bodies with return springs, nonlinear (Duffing) springs, the hybrid kidney
(surface + centerline skeleton), the simplified medial representation (SMRM) of vessels and local
deformation by a static patch solve -- the C++ engine of MedSpring, bound with pybind11 (no second
implementation). Units: millimetre, gram, millisecond, newton.

    import medspring as ms
    sim = ms.Simulation(ms.hybrid_kidney_phantom())            # 458 surface nodes + 42 atoms
    sim.set_loads([ms.PointLoad(node=223, force=(0, 0, -1.0), t_release=500)])
    sim.update(nsteps=2000)                                     # 1000 ms, GIL released
    sim.surface                                                 # (458, 3) read-only view, mm
    sim.positions[0] += (0, 0, 1)                               # writable zero-copy view of the state

Errors: bad input raises medspring.InvalidInput (a ValueError), unreadable files medspring.IoError
(an OSError), failed solves medspring.SolverError (a RuntimeError); all derive from medspring.Error
and carry the C++ message.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from . import _medspring
from ._medspring import *  # noqa: F401,F403  (the engine API)
from ._medspring import Error, InvalidInput, IoError, SolverError, __version__  # noqa: F401

__all__ = [name for name in dir(_medspring) if not name.startswith("_")] + [
    "data_file",
    "press_release",
    "static_force_displacement",
    "__version__",
]


def data_file(name: str) -> Path:
    """Absolute path of a real-anatomy data file: $MEDSPRING_DATA/name, else the folder configured at
    build time (default ../shared/data beside the source tree). Raises IoError when it does not exist."""
    if _medspring.has_io:
        return Path(_medspring.find_data_file(name)).resolve()
    folder = os.environ.get("MEDSPRING_DATA", "")
    path = Path(folder) / name
    if not folder or not path.is_file():
        raise IoError(f"data file {name} not found in '{folder}' (set MEDSPRING_DATA)")
    return path.resolve()


def _as_body_and_model(target):
    if isinstance(target, _medspring.Body):
        return target, target.model
    if isinstance(target, _medspring.Model):
        return None, target
    raise InvalidInput(f"target: expected a Body or a Model; got a {type(target).__name__}")


def static_force_displacement(
    target,
    node: int,
    direction: Sequence[float],
    forces: Iterable[float],
    settings: "StaticSettings | None" = None,
    return_positions: bool = False,
):
    """Quasi-static force-displacement curve of a poke (§2.4 static equilibrium at every force level).

    target: a Body (the force acts on surface node `node` and is transferred to the DOFs; the
    displacement is that of the displayed surface node) or a Model (force on DOF `node`).
    direction: force direction (normalised here); forces: force magnitudes in N, solved in the given
    order, each level starting from the previous equilibrium (continuation).
    Returns the displacement of the node along `direction` (mm) for every force, as an array; with
    return_positions=True also the list of equilibrium DOF positions. Raises SolverError when a level
    has no equilibrium.
    """
    body, model = _as_body_and_model(target)
    d = np.asarray(direction, dtype=np.float64)
    if d.shape != (3,) or not np.all(np.isfinite(d)) or np.linalg.norm(d) == 0:
        raise InvalidInput("direction: expected 3 finite numbers, not all zero")
    d = d / np.linalg.norm(d)
    settings = settings if settings is not None else _medspring.StaticSettings()
    n = model.num_nodes
    if body is not None:
        if not 0 <= node < body.num_surface_nodes:
            raise InvalidInput(f"node: index {node} out of range [0, {body.num_surface_nodes})")
        unit_f = body.transfer_force(node, d)
        rest = body.rest_surface[node].copy()
    else:
        if not 0 <= node < n:
            raise InvalidInput(f"node: index {node} out of range [0, {n})")
        unit_f = np.zeros((n, 3))
        unit_f[node] = d
        rest = model.x0[node].copy()
    x = None
    out, positions = [], []
    state = _medspring.make_state(model) if body is not None else None
    for F in forces:
        res = _medspring.static_equilibrium(model, float(F) * unit_f, settings, x)
        x = np.array(res.x)
        if body is not None:
            state.x = x
            p = body.map_to_surface(state)[node]
        else:
            p = x[node]
        out.append(float(np.dot(p - rest, d)))
        if return_positions:
            positions.append(x)
    out = np.asarray(out)
    return (out, positions) if return_positions else out


def press_release(
    body,
    node: int,
    force: Sequence[float],
    t_ramp: float = 20.0,
    t_release: float = 500.0,
    t_end: float = 1000.0,
    settings: "SimulationSettings | None" = None,
):
    """The press-and-release experiment of §7.1: `force` (N) on surface node `node`, ramped over t_ramp,
    held until t_release, released, run to t_end (ms). Returns a dict of arrays: time (ms, end of every
    frame), contact (|displacement| of the node, mm), max_displacement (over the surface, mm), and the
    Simulation itself under "sim"."""
    sim = _medspring.Simulation(body, settings if settings is not None else _medspring.SimulationSettings())
    sim.set_loads([_medspring.PointLoad(node=node, force=force, t_ramp=t_ramp, t_release=t_release)])
    rest = body.rest_surface
    surface = sim.surface  # zero-copy view, refreshed in place by every update
    frames = int(round(t_end / sim.settings.step.dt))
    time = np.empty(frames)
    contact = np.empty(frames)
    max_disp = np.empty(frames)
    for i in range(frames):
        sim.update()
        time[i] = sim.time
        contact[i] = np.linalg.norm(surface[node] - rest[node])
        max_disp[i] = np.sqrt(((surface - rest) ** 2).sum(axis=1).max())
    return {"time": time, "contact": contact, "max_displacement": max_disp, "sim": sim}


# Scenes in-process (medspring.scenes) and parameter studies on Dask (medspring.study, docs/studies.md).
if getattr(_medspring, "has_scene", False):
    from .scenes import run_scene, scene_document  # noqa: E402,F401

    __all__ += ["run_scene", "scene_document"]

# The paper's study as a library (medspring.paper.run, docs/paper.md).
if getattr(_medspring, "has_paper", False):
    from . import paper  # noqa: E402,F401
