"""`medspring study STUDY --out DIR [--scheduler ADDR | --workers N] [--resume] [--yes] ...`: runs a
parameter study (docs/studies.md). The switches are declared once, in C++ (scene/study_switches.hpp),
and read here through medspring.study_runner_cli(); `python3 -m medspring.study --help` lists them.
Errors are one line on stderr with exit code 2."""

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


class _Parser(argparse.ArgumentParser):
    """An argument mistake is one line naming the switch, exit status 2 (as `medspring study`'s own)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: {message}\n")


def _integer(name: str, least: int):
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer (got '{text}')") from None
        if v < least:
            raise argparse.ArgumentTypeError(f"must be >= {least} (got {v})")
        return v

    parse.__name__ = name  # argparse names the type in some messages
    return parse


def parser() -> argparse.ArgumentParser:
    """The runner's argparse parser, built from the switches declared once in C++
    (scene/study_switches.hpp, medspring.study_runner_cli()); `medspring study` is built from the same
    list. A switch's value is the attribute of its name with '-' as '_' (--no-report: a.no_report)."""
    from .. import study_runner_cli

    d = study_runner_cli()
    p = _Parser(prog="medspring study", description=d["about"].replace("\n", " "))
    p.add_argument(d["positional"].lower(), metavar=d["positional"], help=d["positional_help"])
    groups = {}
    for s in d["switches"]:
        where = p
        if s["group"]:
            if s["group"] not in groups:
                groups[s["group"]] = p.add_mutually_exclusive_group()
            where = groups[s["group"]]
        shown = s["help"] + (f" [{s['unit']}]" if s["unit"] else "") + (
            f" (default: {s['default']})" if s["default"] else "")
        kw = {"dest": s["name"].replace("-", "_"), "help": argparse.SUPPRESS if s["hidden"] else shown}
        if s["type"] == "flag":
            kw["action"] = "store_true"
        else:
            kw["metavar"] = s["value"]
            kw["default"] = None
            if s["required"]:
                kw["required"] = True
            if s["type"] == "integer":
                kw["type"] = _integer(s["name"], s["min"])
                if s["default"].lstrip("-").isdigit():
                    kw["default"] = int(s["default"])
            elif s["type"] == "choice":
                kw["choices"] = s["value"].split("|")
                kw["default"] = s["default"] or None
        where.add_argument("--" + s["name"], **kw)
    return p


def main(argv=None) -> int:
    a = parser().parse_args(argv)
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
    workers = a.workers
    if a.device == "cuda" and workers is None and a.scheduler is None:
        workers = 0  # one process drives the card: each task's runs are one batch on it

    from .. import Error
    from . import measure_scaling, run
    from .report import write_report
    from .spec import load_study
    from .store import Store

    try:
        st = load_study(a.study, settings=a.set)
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
