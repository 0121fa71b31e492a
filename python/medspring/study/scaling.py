"""Throughput of a study's runs on 1..N local workers (the report's scaling table)."""

from __future__ import annotations

import json
import time

from .run import _task, local_client
from .worker import run_batch


def measure_scaling(st, workers_list, runs: int) -> list:
    """For each worker count: a LocalCluster, one warm-up task per worker (builds the model), then the
    first `runs` runs of the study as tasks; returns [{"workers", "runs", "wall_seconds"}]. Nothing is
    written to the study's store."""
    scene_json = json.dumps(st.scene)
    nb = min(st.num_batches, max(1, -(-runs // st.batch)))
    tasks = [_task(st, b, scene_json)[1] for b in range(nb)]
    n_runs = sum(len(t["runs"]) for t in tasks)
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
