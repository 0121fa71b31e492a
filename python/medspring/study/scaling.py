"""Throughput of a study's runs on 1..N local workers (the report's scaling table)."""

from __future__ import annotations

import json
import time

from .run import _task, local_client
from .worker import run_batch


def measure_scaling(st, workers_list, runs: int) -> list:
    """For each worker count: a LocalCluster, one warm-up task per worker (builds the model), then the
    first `runs` runs of the study as 4 x max(workers_list) equal tasks (so that every worker count
    gets an even share); returns [{"workers", "runs", "wall_seconds"}]. Nothing is written to the
    study's store."""
    scene_json = json.dumps(st.scene)
    n_runs = min(runs, st.num_runs)
    parts = max(1, min(n_runs, 4 * max(workers_list)))
    every = [(i, st.params(i)) for i in range(n_runs)]
    base = _task(st, 0, scene_json)[1]
    tasks = [dict(base, batch=k, runs=every[k::parts]) for k in range(parts)]
    out = []
    for w in workers_list:
        client, cluster = local_client(w)
        try:
            client.wait_for_workers(w, timeout=60)
            warm = [dict(tasks[0], runs=tasks[0]["runs"][:1]) for _ in range(w)]
            client.gather(client.map(run_batch, warm, pure=False))
            t0 = time.perf_counter()
            client.gather(client.map(run_batch, tasks, pure=False))
            out.append({"workers": w, "runs": n_runs, "wall_seconds": time.perf_counter() - t0})
        finally:
            client.close()
            cluster.close()
    return out
