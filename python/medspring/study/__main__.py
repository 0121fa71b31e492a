"""`medspring study STUDY --out DIR [--scheduler tcp://HOST:PORT | --workers N] [--resume] [--yes]
[--set N=V] [--device cpu|cuda|cpu-batch|auto]`:
runs a parameter study (docs/studies.md). Errors are one line on stderr with exit code 2."""

from __future__ import annotations

import argparse
import os
import sys


def _cuda_refusal() -> str:
    """Why --device cuda cannot run here ("" when it can): no CUDA backend in the build or no usable
    device (docs/gpu.md, "Study runs on the GPU")."""
    try:
        from .. import gpu
    except ImportError as e:  # the compiled module itself is missing
        return f"the medspring package cannot be imported ({e})"
    if not gpu.built():
        return "this build has no CUDA backend (MEDSPRING_CUDA, docs/gpu.md)"
    ok, why = gpu.available()
    if not ok:
        return why.splitlines()[0] if why else "no usable CUDA device"
    return ""


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="medspring study",
        description="Run a parameter study on Dask distributed: every run a task on the C++ engine, results "
        "streamed to DIR/results.zarr and DIR/summary.csv, a report in DIR/study.md.",
    )
    p.add_argument("study", help="study file (JSON, docs/studies.md)")
    p.add_argument("--out", required=True, help="output folder (new, empty, or this study's with --resume)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", help="address of a running dask-scheduler, tcp://HOST:PORT")
    where.add_argument(
        "--workers", type=int, help="local worker processes (default: every core; 0: in this process, no Dask)"
    )
    p.add_argument("--resume", action="store_true", help="complete the study already in --out (only missing runs)")
    p.add_argument("--yes", action="store_true", help="run a study with more runs than its max_runs")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--no-report", action="store_true", help="do not write study.md")
    p.add_argument("--scaling", type=int, metavar="RUNS", default=0,
                   help="also time RUNS runs on 1..N local workers (N = --workers or every core) for the report")
    p.add_argument("--max-batches", type=int, default=None, help=argparse.SUPPRESS)
    p.add_argument("--set", dest="settings", metavar="NAME=VALUE[,NAME=VALUE]", default=None,
                   help="override the study file's declared settings: samples.count, samples.method, seed, "
                   "batch, max_runs (docs/parameters.md)")
    p.add_argument("--device", choices=["cpu", "cuda", "cpu-batch", "auto"], default="cpu",
                   help="where the runs step: cpu (default: each run a scene run), cuda (each task's runs one "
                   "batch on the GPU engine; in this process unless --workers/--scheduler), cpu-batch (the "
                   "same batch path on the CPU engine, the reference of cuda) or auto (cuda where a GPU is "
                   "usable, else cpu, saying which and why); docs/gpu.md")
    a = p.parse_args(argv)
    if a.device == "auto":  # the only fallback, asked for: said in one line
        why = _cuda_refusal()
        a.device = "cpu" if why else "cuda"
        print(f"medspring study: --device auto: {'the CPU engine (' + why + ')' if why else 'the GPU engine'}",
              file=sys.stderr)
    if a.device == "cuda":
        # No silent fallback (docs/gpu.md): a build without the CUDA backend or a machine without a usable
        # device is refused in one line naming the reason and --device cpu.
        why = _cuda_refusal()
        if why:
            cause = why.split("; use the CPU engine")[0]  # the engine's own hint names the wrong switch here
            print(f"medspring study: --device cuda: {cause}; run it on the CPU engine with --device cpu",
                  file=sys.stderr)
            return 2
    if a.workers is not None and a.workers < 0:
        print("medspring study: --workers: must be >= 0", file=sys.stderr)
        return 2
    workers = a.workers
    if a.device == "cuda" and workers is None and a.scheduler is None:
        workers = 0  # one process drives the card: each task's runs are one batch on it

    from .. import Error
    from . import measure_scaling, run
    from .report import write_report
    from .spec import load_study
    from .store import Store

    try:
        st = load_study(a.study, settings=a.settings)
        df = run(st, out=a.out, scheduler=a.scheduler, workers=workers, resume=a.resume, yes=a.yes,
                 progress=not a.quiet, report=not a.no_report, max_batches=a.max_batches, device=a.device)
        if a.scaling > 0:
            n = a.workers or os.cpu_count() or 1
            store = Store(__import__("pathlib").Path(a.out), st, create=False)
            store.g.attrs["scaling"] = measure_scaling(st, list(range(1, n + 1)), a.scaling)
            if not a.no_report:
                write_report(store, store.frame())
    except (Error, OSError) as e:
        msg = str(e).splitlines()[0] if str(e) else type(e).__name__
        print(f"medspring study: {msg}", file=sys.stderr)
        return 2
    except Exception as e:  # anything else (a lost scheduler, a full disk): one line, the folder stays resumable
        msg = str(e).splitlines()[0] if str(e) else ""
        print(f"medspring study: {type(e).__name__}: {msg} (resume with --resume)", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("medspring study: interrupted (the folder is resumable: --resume)", file=sys.stderr)
        return 130
    failed = int(df["failed"].sum())
    print(f"{a.out}: {len(df)} runs done, {failed} failed", file=sys.stderr if a.quiet else sys.stdout)
    return 0


if __name__ == "__main__":
    sys.exit(main())
