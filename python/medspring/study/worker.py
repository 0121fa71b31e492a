"""The task a Dask worker executes: one batch of study runs on the C++ engine, in the worker process.

A batch is a plain dict (picklable, no Study object): the base scene as JSON, the parameter overrides of
each run, what to return. The model is built once per worker thread (SceneRunner cache) and reused by
every later run on the same model, so a task of many small runs costs little more than the runs.
"""

from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from ..scenes import apply_overrides, scene_runner


def run_batch(task: dict) -> dict:
    """Runs every run of `task` and returns arrays over them: index, metrics (n, M), failed (n,),
    errors (list of str), load_node (n,), load_force (n, 3), fields (n, T, S, 3) when asked,
    engine_seconds (n,), and the task's wall time. A run that raises or diverges (non-finite metrics)
    is marked failed with its error; the batch itself never fails for a bad run."""
    t0 = time.perf_counter()
    # Tests stretch every task by this many seconds so that a worker or client killed "mid-study" is
    # killed mid-study on a fast machine too; results do not depend on it.
    delay = float(os.environ.get("MEDSPRING_STUDY_TASK_DELAY", "0") or 0)
    if delay > 0:
        time.sleep(delay)
    base = json.loads(task["scene"])
    runner = scene_runner()
    runs = task["runs"]
    n = len(runs)
    metrics = task["metrics"]
    times = task["field_times"]
    S = task["num_surface_nodes"]
    want_fields = bool(times)
    dtype = np.dtype(task["field_dtype"])
    out_metrics = np.full((n, len(metrics)), np.nan)
    failed = np.zeros(n, dtype=np.uint8)
    errors = [""] * n
    load_node = np.full(n, -1, dtype=np.int64)
    load_force = np.full((n, 3), np.nan)
    engine = np.zeros(n)
    fields = np.full((n, len(times), S, 3), np.nan, dtype=dtype) if want_fields else None
    device = task.get("device", "cpu")
    batched: list = []
    if device in ("cuda", "cpu-batch"):
        # The batch engine (docs/gpu.md, "Study runs on the GPU"): every run of the task built here and
        # stepped together; a run whose build fails comes back as its error text. A GPU failure (no device,
        # an unsupported model) raises: the study stops with it rather than recording every run failed.
        docs = []
        for index, overrides in runs:
            try:
                docs.append(json.dumps(apply_overrides(base, overrides)))
            except Exception as e:  # a bad override: the run fails, the batch goes on without it
                docs.append(e)
        good = [d for d in docs if isinstance(d, str)]
        origins = [f"run {index}" for (index, _), d in zip(runs, docs) if isinstance(d, str)]
        results = runner.run_batch(good, "/", times, want_fields, "cuda" if device == "cuda" else "cpu", origins)
        it = iter(results)
        batched = [next(it) if isinstance(d, str) else d for d in docs]
    for k, (index, overrides) in enumerate(runs):
        try:
            if batched:
                r = batched[k]
                if isinstance(r, Exception):
                    raise r
                if isinstance(r, str):  # the build's error, "InvalidInput: run 17: ..." as below
                    failed[k] = 1
                    errors[k] = r.splitlines()[0][:500]
                    continue
            else:
                doc = apply_overrides(base, overrides)
                r = runner.run(json.dumps(doc), "/", f"run {index}", times, want_fields)
            s = r["summary"]
            out_metrics[k] = [float(s[m]) for m in metrics]
            load_node[k] = r["load_node"]
            load_force[k] = r["load_force"]
            engine[k] = r["build_seconds"] + r["run_seconds"]
            bad = [m for m in ("contact_peak_mm", "max_disp_peak_mm", "final_max_disp_mm") if not math.isfinite(s[m])]
            if bad:
                failed[k] = 1
                errors[k] = f"diverged: {bad[0]} is not finite ({s['warnings']} numerical warnings)"
            elif want_fields:
                if r["fields"].shape[1] != S:
                    raise ValueError(f"the run's model has {r['fields'].shape[1]} surface nodes, the study's {S}")
                fields[k] = r["fields"]
        except Exception as e:  # a bad run is recorded, never fatal to the study
            failed[k] = 1
            errors[k] = f"{type(e).__name__}: {e}".splitlines()[0][:500]
    return {
        "batch": task["batch"],
        "index": np.array([i for i, _ in runs], dtype=np.int64),
        "metrics": out_metrics,
        "failed": failed,
        "errors": errors,
        "load_node": load_node,
        "load_force": load_force,
        "fields": fields,
        "engine_seconds": engine,
        "task_seconds": time.perf_counter() - t0,
    }
