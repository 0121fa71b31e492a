"""Running a study on Dask distributed: every batch of runs is one task executed by a worker process;
finished batches stream into the study folder's Zarr store and summary CSV as they complete.

    from medspring import study
    df = study.run("examples/studies/kidney_stiffness.json", out="out/stiffness")       # LocalCluster
    df = study.run(spec, out="out/s", client=distributed.Client("tcp://host:8786"))     # a cluster
"""

from __future__ import annotations

import json
import os
import socket
import sys
import time
from pathlib import Path
from typing import Any

from .._medspring import InvalidInput
from .spec import Study, load_study
from .store import Store, check_folder
from .worker import run_batch

# Seconds to reach a scheduler before giving up ($MEDSPRING_STUDY_CONNECT_TIMEOUT overrides).
CONNECT_TIMEOUT_S = float(os.environ.get("MEDSPRING_STUDY_CONNECT_TIMEOUT", "6"))


class SchedulerUnreachable(InvalidInput):
    """The scheduler address does not answer."""


def connect(scheduler: str, timeout: float = CONNECT_TIMEOUT_S):
    """A distributed.Client on `scheduler` (tcp://HOST:PORT), or InvalidInput within ~timeout s."""
    import distributed

    if not isinstance(scheduler, str) or "://" not in scheduler:
        raise InvalidInput(f"--scheduler: expected an address like tcp://HOST:PORT; got {scheduler!r}")
    try:
        return distributed.Client(scheduler, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError) as e:
        msg = str(e).splitlines()[0] if str(e) else type(e).__name__
        raise SchedulerUnreachable(
            f"--scheduler {scheduler}: cannot reach the scheduler within {timeout:g} s ({msg[:160]})"
        ) from None


def local_client(workers: int | None):
    """A LocalCluster of `workers` single-threaded worker processes (default: every core)."""
    import distributed

    n = workers or os.cpu_count() or 1
    cluster = distributed.LocalCluster(
        n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=40
    )
    return distributed.Client(cluster, set_as_default=False), cluster


def _task(st: Study, b: int, scene_json: str, device: str = "cpu") -> tuple:
    sl = range(b * st.batch, min(st.num_runs, (b + 1) * st.batch))
    runs = [(i, st.params(i)) for i in sl]
    return runs, {
        "batch": b,
        "scene": scene_json,
        "runs": runs,
        "metrics": st.metrics,
        "field_times": st.field_times,
        "field_dtype": st.field_dtype,
        "num_surface_nodes": st.num_surface_nodes,
        "device": device,
    }


def _failed_batch(st: Study, b: int, runs: list, error: Exception) -> dict:
    """The result of a batch whose task failed as a whole: every run failed with the task's error."""
    import numpy as np

    n = len(runs)
    msg = f"task failed: {type(error).__name__}: {error}".splitlines()[0][:500]
    return {
        "batch": b,
        "index": np.array([i for i, _ in runs], dtype=np.int64),
        "metrics": np.full((n, len(st.metrics)), np.nan),
        "failed": np.ones(n, dtype=np.uint8),
        "errors": [msg] * n,
        "load_node": np.full(n, -1, dtype=np.int64),
        "load_force": np.full((n, 3), np.nan),
        "fields": np.full((n, len(st.field_times), st.num_surface_nodes, 3), np.nan, dtype=st.field_dtype)
        if st.field_times
        else None,
        "engine_seconds": np.zeros(n),
        "task_seconds": 0.0,
    }


def _progress(total: int, initial: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(
        total=total,
        initial=initial,
        unit="run",
        disable=not enabled,
        file=sys.stderr,
        dynamic_ncols=True,
        smoothing=0.1,
    )


def run(
    study: Any,
    out: str | os.PathLike,
    client=None,
    scheduler: str | None = None,
    workers: int | None = None,
    resume: bool = False,
    yes: bool = False,
    progress: bool = True,
    report: bool = True,
    csv_every_s: float = 2.0,
    max_batches: int | None = None,
    device: str = "cpu",
    settings: Any = None,
):
    """Runs a study (file, JSON text, dict or Study) into the folder `out` and returns the summary table
    (pandas DataFrame of the finished runs).

    client: a distributed.Client to use; else scheduler: an address (tcp://HOST:PORT) to connect to
    (InvalidInput within 10 s when it does not answer); else a LocalCluster of `workers` processes
    (default every core). workers=0 runs every batch in this process without Dask (the 1-process
    reference). resume: complete the study already in `out` (only missing batches are run). yes: allow
    more runs than the study's max_runs (default 100000). max_batches: stop after that many batches
    (tests; the folder stays resumable). device: "cpu" (each run a scene run), "cuda" (each batch of runs
    stepped together on the GPU engine, docs/gpu.md "Study runs on the GPU") or "cpu-batch" (the same
    batch path on the CPU engine). settings: overrides of the study file's declared settings
    (samples.count, samples.method, seed, batch, max_runs; docs/parameters.md), as load_study takes them.
    Everything is validated, and the scheduler reached, before anything is written."""
    if device not in ("cpu", "cuda", "cpu-batch"):
        raise InvalidInput(f"device: expected 'cpu', 'cuda' or 'cpu-batch'; got {device!r}")
    st = study if isinstance(study, Study) else load_study(study, settings=settings)
    if st.num_runs > st.max_runs and not yes:
        raise InvalidInput(
            f"{st.origin}: the study has {st.num_runs} runs, more than max_runs = {st.max_runs}: "
            "pass --yes (yes=True) to run it anyway"
        )
    out = Path(out)
    existing = check_folder(out, st, resume)

    own_cluster = None
    own_client = None
    if workers == 0 and client is None and scheduler is None:
        pool = None
    elif client is not None:
        pool = client
    elif scheduler is not None:
        pool = own_client = connect(scheduler)
    else:
        own_client, own_cluster = local_client(workers)
        pool = own_client
    try:
        store = Store(out, st, create=not existing)
        return _drive(st, store, pool, progress, report, csv_every_s, max_batches, device)
    finally:
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()


def _drive(st: Study, store: Store, pool, progress: bool, report: bool, csv_every_s: float, max_batches,
           device: str = "cpu"):
    scene_json = json.dumps(st.scene)
    missing = store.missing_batches()
    if max_batches is not None:
        missing = missing[:max_batches]
    done0, failed0 = store.num_done()
    bar = _progress(st.num_runs, done0, progress)
    failed = failed0
    t_start = time.perf_counter()
    last_csv = 0.0
    written: set = set()
    engine_total = 0.0  # engine seconds of the runs written in this session
    duplicates = 0
    nworkers = 1

    def finish(b: int, runs, result):
        nonlocal failed, last_csv, duplicates, engine_total
        if b in written:
            duplicates += 1  # a rescheduled task finishing twice: its result is already stored
            return
        store.write(b, runs, result)
        engine_total += float(result["engine_seconds"].sum())
        written.add(b)
        failed += int(result["failed"].sum())
        bar.update(len(runs))
        bar.set_postfix(failed=failed, refresh=False)
        now = time.perf_counter()
        if now - last_csv >= csv_every_s:
            store.write_csv()
            last_csv = now

    if pool is None:
        for b in missing:
            runs, task = _task(st, b, scene_json, device)
            finish(b, runs, run_batch(task))
    else:
        from distributed import KilledWorker, as_completed

        nworkers = max(1, len(pool.scheduler_info().get("workers", {})))
        window = max(4, 4 * nworkers)  # batches in flight: keeps every worker busy, memory bounded
        pending = iter(missing)
        tasks: dict = {}
        fp = st.fingerprint()

        def submit():
            b = next(pending, None)
            if b is None:
                return None
            runs, task = _task(st, b, scene_json, device)
            fut = pool.submit(run_batch, task, key=f"medspring-study-{fp}-{b}", pure=False, retries=1)
            tasks[fut.key] = (b, runs)
            return fut

        first = [f for f in (submit() for _ in range(window)) if f is not None]
        ac = as_completed(first, loop=pool.loop)
        for fut in ac:
            b, runs = tasks.pop(fut.key)
            try:
                result = fut.result()
            except KilledWorker as e:  # the task killed every worker it ran on: its runs failed
                result = _failed_batch(st, b, runs, e)
            finish(b, runs, result)
            fut.release()
            nxt = submit()
            if nxt is not None:
                ac.add(nxt)
        try:
            nworkers = max(1, len(pool.scheduler_info().get("workers", {})))
        except Exception:  # the scheduler may be gone already; the count is only for the report
            pass
    bar.close()
    wall = time.perf_counter() - t_start
    store.write_csv()
    meta = {
        "wall_seconds": wall,
        "runs_this_session": sum(len(range(*store.batch_slice(b).indices(st.num_runs))) for b in written),
        "workers": nworkers if pool is not None else 0,
        "engine_seconds": engine_total,
        "duplicates_ignored": duplicates,
        "host": socket.gethostname(),
        "device": device,
    }
    sessions = list(store.g.attrs.get("sessions", []))
    sessions.append(meta)
    store.g.attrs["sessions"] = sessions
    frame = store.frame()
    if report and len(store.missing_batches()) == 0:
        from .report import write_report

        write_report(store, frame)
    return frame
