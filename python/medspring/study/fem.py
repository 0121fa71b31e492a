"""FEM reference solves and calibration on Dask distributed (docs/studies.md, docs/accuracy.md).

Each CalculiX reference solve (medspring.fem_reference: one closed surface, one material, one contact-disk
load) is one Dask task in a worker process; many loads and materials are solved in parallel, on a
LocalCluster or on a cluster given by its scheduler address. The calibration loop (medspring.calibrate)
then fits the hybrid model to the training references the cluster solved, and the held-out references
are solved in the same pass.

    from medspring.study import fem
    refs = fem.references(V, F, [{"centre": c, "force": f, "E_kPa": e} for ...], workers=2)
    fit = fem.calibrate(V, F, atoms, train_centres, train_forces, held_out=[...], client=client)

* Deterministic: a case's result depends only on its inputs (the engine and ccx are deterministic, and
  the results come back in the order of the cases), so a distributed run equals the serial one bit for
  bit (checked in python/tests/test_study_fem.py).
* The FEM cache is respected: every worker looks up / stores its solve in $MEDSPRING_FEM_CACHE (keyed by
  a hash of the input deck); LocalCluster workers inherit the client's environment. On a multi-machine
  cluster, point $MEDSPRING_FEM_CACHE at a folder every worker reaches to share it.
* A case that fails (bad material, open surface, CalculiX error) is recorded with its error, not fatal:
  its result has ok = False and error = the one-line message; the other cases finish.
"""

from __future__ import annotations

import time
from typing import Any, Sequence

import numpy as np

from .._medspring import InvalidInput

try:
    from .._medspring import FemCaseSettings
except ImportError:  # a build without the FEM layer (no fem_reference either): the module still imports
    FemCaseSettings = None

# fem_reference's keyword arguments a case may set (the rest come from the defaults given to references()):
# the declared FemCaseSettings (scene/study_settings.hpp, docs/parameters.md) and the support direction.
_CASE = FemCaseSettings() if FemCaseSettings is not None else None
CASE_KEYS = tuple(spec["name"] for spec in getattr(FemCaseSettings, "_params", ())) + ("support_direction",)


def _default(name: str):
    return getattr(_CASE, name, None)



def solve_case(vertices: np.ndarray, faces: np.ndarray, case: dict) -> dict:
    """One reference solve (the Dask task): fem_reference on the case, or its error recorded."""
    import medspring as ms

    t0 = time.perf_counter()
    kw = {k: case[k] for k in CASE_KEYS if k in case}
    try:
        r = ms.fem_reference(vertices, faces, case["centre"], case["force"], **kw)
        return {"ok": True, "error": "", "displacement": r["displacement"], "disk_mean": r["disk_mean"],
                "solve_seconds": r["solve_seconds"], "fem_nodes": int(r["fem_nodes"]),
                "task_seconds": time.perf_counter() - t0}
    except Exception as e:  # recorded per case, not fatal to the others
        msg = f"{type(e).__name__}: {e}".splitlines()[0][:500]
        return {"ok": False, "error": msg, "displacement": None, "solve_seconds": 0.0, "fem_nodes": 0,
                "task_seconds": time.perf_counter() - t0}


def _cases(cases: Sequence[dict], defaults: dict) -> list[dict]:
    out = []
    for k, c in enumerate(cases):
        if not isinstance(c, dict) or "centre" not in c or "force" not in c:
            raise InvalidInput(f"cases[{k}]: expected a dict with 'centre' and 'force' (and optionally "
                               f"{', '.join(CASE_KEYS)})")
        unknown = set(c) - set(CASE_KEYS) - {"centre", "force"}
        if unknown:
            raise InvalidInput(f"cases[{k}]: unknown key {sorted(unknown)[0]!r} (expected centre, force, "
                               f"{', '.join(CASE_KEYS)})")
        merged = dict(defaults)
        merged.update(c)
        merged["centre"] = [float(x) for x in np.asarray(c["centre"], dtype=float).reshape(3)]
        merged["force"] = [float(x) for x in np.asarray(c["force"], dtype=float).reshape(3)]
        out.append(merged)
    return out


def _with_client(client, scheduler, workers):
    """(client, closer): the given client, one connected to `scheduler`, a LocalCluster of `workers`
    processes, or (None, None) for workers == 0 (everything in this process)."""
    from .run import connect, local_client

    if client is not None:
        return client, None
    if scheduler is not None:
        c = connect(scheduler)
        return c, c.close
    if workers == 0:
        return None, None
    c, cluster = local_client(workers)

    def close():
        c.close()
        cluster.close()

    return c, close


def references(
    vertices: Any,
    faces: Any,
    cases: Sequence[dict],
    client=None,
    scheduler: str | None = None,
    workers: int | None = None,
    **defaults,
) -> list[dict]:
    """FEM reference displacements of the closed surface (vertices (V, 3) mm, faces (F, 3)) for every case,
    solved as Dask tasks. A case is a dict: centre (mm), force (N) and optionally E_kPa, nu, radius,
    support_direction, support_depth, level (fem_reference's arguments; `defaults` fills the rest).
    client / scheduler (tcp://HOST:PORT) / workers (a LocalCluster of N processes; 0: in this process).
    Returns one dict per case, in the order of the cases: ok, error, displacement (V, 3) or None,
    disk_mean (3,) (the mean displacement over the loaded disk; only when ok), solve_seconds, fem_nodes,
    task_seconds."""
    V = np.ascontiguousarray(vertices, dtype=float)
    F = np.ascontiguousarray(faces, dtype=np.int64)
    unknown = set(defaults) - set(CASE_KEYS)
    if unknown:
        raise InvalidInput(f"references: unknown argument {sorted(unknown)[0]!r} (expected {', '.join(CASE_KEYS)})")
    cs = _cases(cases, defaults)
    if not cs:
        return []
    c, close = _with_client(client, scheduler, workers)
    try:
        if c is None:
            return [solve_case(V, F, case) for case in cs]
        # hash=False: fresh keys per call (a hashed key could be released by a previous call meanwhile).
        Vf, Ff = c.scatter(V, broadcast=True, hash=False), c.scatter(F, broadcast=True, hash=False)
        # pure=False: a case is solved once per call (the FEM cache, not Dask's, deduplicates solves).
        futures = [c.submit(solve_case, Vf, Ff, case, pure=False)
                   for k, case in enumerate(cs)]
        out = []
        for k, f in enumerate(futures):
            try:
                out.append(f.result())
            except Exception as e:  # the task as a whole failed (e.g. KilledWorker): recorded
                msg = f"task failed: {type(e).__name__}: {e}".splitlines()[0][:500]
                out.append({"ok": False, "error": msg, "displacement": None, "solve_seconds": 0.0,
                            "fem_nodes": 0, "task_seconds": 0.0})
        return out
    finally:
        if close is not None:
            close()


def calibrate(
    vertices: Any,
    faces: Any,
    atoms: Any,
    centres: Any,
    forces: Any,
    held_out: Sequence[dict] = (),
    E_kPa: float = _default("E_kPa"),
    nu: float = _default("nu"),
    radius: float = _default("radius"),
    support_direction=(0.0, 0.0, -1.0),
    support_depth: float = _default("support_depth"),
    nonlinear: bool = True,
    client=None,
    scheduler: str | None = None,
    workers: int | None = None,
    site_readout: str = "node",
    train_forces: Any = None,
    site_weight: float | None = None,
) -> dict:
    """medspring.calibrate with its FEM reference solves run as Dask tasks: the training loads (force rows
    `forces` (L, 3) N over contact disks at `centres` (L, 3)) and the `held_out` cases (dicts with centre
    and force) are solved in one parallel pass; the hybrid model is fitted to the training cases that
    solved, then evaluated on the held-out ones. Returns a dict: parameters (k_surf, k_spoke, k_cl, k_r,
    k_loc, support), training (one dict per training load: ok, error, solve_seconds), held_out (per case:
    ok, error, contact_fem, contact_model, contact_error, rms_error), fem_seconds (wall time of the solves).
    A failed training solve is dropped from the fit and recorded; InvalidInput when none solved.
    site_readout: 'node' or 'disk-mean', medspring.calibrate's (checked there, by the rules of `medspring
    calibrate --site-readout`); with 'disk-mean' the solved disk means go in as fem_disk_means.
    train_forces: a force in N or a list of such, medspring.calibrate's (the rules of `medspring calibrate
    --train-force`, checked before any solve): every centre is loaded at each magnitude along its force row's
    direction, centre-major (medspring.training_loads), and those loads are solved and fitted.
    site_weight: the weight of the site term, medspring.calibrate's (`--site-weight`; None: its default, 1)."""
    import medspring as ms

    C = np.asarray(centres, dtype=float).reshape(-1, 3)
    Fs = np.asarray(forces, dtype=float).reshape(-1, 3)
    if C.shape[0] == 0 or Fs.shape[0] != C.shape[0]:
        raise InvalidInput(f"calibrate: expected L >= 1 centres and as many forces; got {C.shape[0]} and {Fs.shape[0]}")
    if train_forces is not None:  # the loads medspring.calibrate would fit, the same doubles (checked there)
        C, Fs = ms.training_loads(C, Fs, train_forces)
    weight = {} if site_weight is None else {"site_weight": site_weight}
    V = np.ascontiguousarray(vertices, dtype=float)
    F = np.ascontiguousarray(faces, dtype=np.int64)
    common = dict(E_kPa=E_kPa, nu=nu, radius=radius, support_direction=tuple(support_direction),
                  support_depth=support_depth, level=1)
    training_cases = [{"centre": C[i], "force": Fs[i]} for i in range(C.shape[0])]
    t0 = time.perf_counter()
    refs = references(V, F, training_cases + list(held_out), client=client, scheduler=scheduler,
                      workers=workers, **common)
    fem_seconds = time.perf_counter() - t0
    train, rest = refs[: C.shape[0]], refs[C.shape[0]:]
    good = [i for i, r in enumerate(train) if r["ok"]]
    if not good:
        raise InvalidInput(f"calibrate: every training solve failed (first: {train[0]['error']})")
    fit = ms.calibrate(V, F, atoms, C[good], Fs[good], E_kPa=E_kPa, nu=nu, radius=radius,
                       support_direction=support_direction, support_depth=support_depth, nonlinear=nonlinear,
                       fem_displacements=[train[i]["displacement"] for i in good], site_readout=site_readout,
                       fem_disk_means=(np.array([train[i]["disk_mean"] for i in good])
                                       if site_readout == "disk-mean" else None), **weight)
    rows = []
    if held_out:
        settings = ms.HybridSettings()
        settings.k_surf, settings.k_spoke, settings.k_cl = fit["k_surf"], fit["k_spoke"], fit["k_cl"]
        settings.surface_node.return_k = fit["k_r"]
        settings.atom_node.return_k = fit["k_r"]
        settings.nonlinear = nonlinear
        settings.fixed = list(fit["support"])
        model = ms.HybridKidney(ms.SurfaceMesh(V, F), np.asarray(atoms, dtype=float), settings)
        for case, r in zip(held_out, rest):
            row = {"ok": r["ok"], "error": r["error"], "centre": np.asarray(case["centre"], dtype=float),
                   "force": np.asarray(case["force"], dtype=float)}
            if r["ok"]:
                u_fem = r["displacement"]
                u = ms.spring_displacement(model, row["centre"], row["force"], radius=radius)
                contact = int(np.argmin(np.linalg.norm(V - row["centre"], axis=1)))
                c_fem = float(np.linalg.norm(u_fem[contact]))
                row.update(contact_fem=c_fem, contact_model=float(np.linalg.norm(u[contact])),
                           contact_error=float(np.linalg.norm(u[contact] - u_fem[contact]) / c_fem),
                           rms_error=float(np.sqrt(np.mean(np.sum((u - u_fem) ** 2, axis=1))) / c_fem))
            rows.append(row)
    return {
        "parameters": fit,
        "training": [{"ok": r["ok"], "error": r["error"], "solve_seconds": r["solve_seconds"]} for r in train],
        "held_out": rows,
        "fem_seconds": fem_seconds,
    }
