"""DIR/study.md: what was varied, sensitivity plots (each metric against each varied parameter,
matplotlib), the summary table and the study's timing (runs per second per worker; scaling from 1 to N
workers when measured with `medspring study --scaling`)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np


def _fmt(x) -> str:
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else ""
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    if isinstance(x, (float, np.floating)):
        if not math.isfinite(x):
            return str(x)
        return f"{x:.4g}"
    return str(x).replace("|", "/")


def _table(df, max_rows: int = 20) -> str:
    cols = list(df.columns)
    lines = ["| " + " | ".join(str(c) for c in cols) + " |", "|" + "---|" * len(cols)]
    for _, row in df.head(max_rows).iterrows():
        lines.append("| " + " | ".join(_fmt(row[c]) for c in cols) + " |")
    if len(df) > max_rows:
        lines.append(f"\n({len(df) - max_rows} more rows in summary.csv)")
    return "\n".join(lines)


def _param_columns(st, df) -> list:
    out = []
    for v in st.vary:
        if v.name in df.columns and np.issubdtype(df[v.name].dtype, np.number):
            out.append((v.path, v.name))
        elif v.width == 3:
            out.append((f"{v.path} (z)", f"{v.name}_z"))
    return out


def sensitivity_plots(store, df) -> list:
    """One PNG per metric: the metric against each varied numeric parameter (failed runs left out)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    st = store.st
    folder = store.out / "plots"
    folder.mkdir(exist_ok=True)
    ok = df[~df["failed"]]
    params = _param_columns(st, ok)
    files = []
    if not params or ok.empty:
        return files
    for m in st.metrics:
        fig, axes = plt.subplots(1, len(params), figsize=(3.6 * len(params), 3.0), squeeze=False)
        for ax, (label, col) in zip(axes[0], params):
            ax.plot(ok[col], ok[m], ".", ms=3, alpha=0.6)
            ax.set_xlabel(label)
            ax.set_ylabel(m)
            ax.grid(alpha=0.3)
        fig.suptitle(f"{st.name}: {m}")
        fig.tight_layout()
        path = folder / f"{m}.png"
        fig.savefig(path, dpi=90)
        plt.close(fig)
        files.append(path)
    return files


def _how(st, v) -> str:
    if v.kind == "values":
        return f"values {v.values[:8]}{' ...' if len(v.values) > 8 else ''}"
    if v.kind == "grid":
        return f"grid of {len(v.values)} from {v.values[0]:g} to {v.values[-1]:g}"
    if v.kind in ("uniform", "log_uniform", "integers"):
        return f"{v.kind.replace('_', '-')} [{v.low:g}, {v.high:g})"
    if v.kind == "choice":
        return f"choice of {v.values}"
    if v.kind == "surface_node":
        return f"random surface node of {st.num_surface_nodes}"
    if v.kind == "surface_point":
        return "random point on the rest surface (uniform by area)"
    return "random unit vector"


def write_report(store, df) -> Path:
    st = store.st
    g = store.g
    lines = [f"# Study {st.name}", ""]
    if st.description:
        lines += [st.description, ""]
    n_failed = int(df["failed"].sum())
    lines += [
        f"{st.num_runs} runs ({len(df)} finished, {n_failed} failed) of the base scene "
        f"`{st.scene.get('name', '')}`; seed {st.seed}; batches of {st.batch} runs; fingerprint "
        f"`{st.fingerprint()}`. Results: `results.zarr` (xarray: `xarray.open_zarr('results.zarr', "
        "consolidated=False, mask_and_scale=False)`), "
        "`summary.csv`.",
        "",
        "## Varied",
        "",
        "| parameter path | how |",
        "|---|---|",
    ]
    for v in st.vary:
        how = _how(st, v)
        if v.sampled:
            how += f" ({st.method}, {st.count} samples)"
        lines.append(f"| `{v.path}` | {how} |")
    if not st.vary:
        lines.append("| (nothing) | the base scene once |")
    lines += ["", "## Sensitivity", ""]
    plots = sensitivity_plots(store, df)
    for p in plots:
        lines.append(f"![{p.stem}](plots/{p.name})")
    if not plots:
        lines.append("(no numeric varied parameter, or no successful run: nothing to plot)")
    ok = df[~df["failed"]]
    lines += ["", "## Summary", ""]
    if not ok.empty:
        desc = ok[st.metrics].describe().T[["mean", "std", "min", "50%", "max"]]
        desc.insert(0, "metric", desc.index)
        lines += [_table(desc, 100), ""]
    lines += ["Runs (first rows; every run in `summary.csv`):", "", _table(df.drop(columns=["error"])), ""]
    if n_failed:
        lines += ["Failed runs:", "", _table(df[df["failed"]][["run", "error"]], 20), ""]
    lines += [
        "## Timing",
        "",
        "| session | runs | workers | wall s | runs/s | runs/s per worker | engine ms/run | overhead ms/run |",
        "|---|---|---|---|---|---|---|---|",
    ]
    engine = float(np.mean(df["engine_seconds"])) if len(df) else 0.0
    for k, s in enumerate(g.attrs.get("sessions", [])):
        runs, w, wall = s["runs_this_session"], max(1, s["workers"]), s["wall_seconds"]
        rate = runs / wall if wall > 0 else float("nan")
        eng = s["engine_seconds"] / runs if runs and "engine_seconds" in s else engine
        over = (wall * w / runs - eng) * 1e3 if runs else float("nan")
        lines.append(
            f"| {k + 1} | {runs} | {s['workers'] or '0 (in process)'} | {wall:.2f} | {rate:.1f} | {rate / w:.1f} | "
            f"{eng * 1e3:.2f} | {over:.2f} |"
        )
    lines += [
        "",
        "engine ms/run: mean build (loads; the model once per worker) + run time inside the C++ engine; "
        "overhead ms/run: wall × workers / runs − engine, i.e. everything else (Dask, transfer, writing "
        "Zarr, this process), per run and worker.",
        "",
    ]
    scaling = g.attrs.get("scaling")
    if scaling:
        lines += ["### Scaling", "", "| workers | runs | wall s | runs/s | speed-up |", "|---|---|---|---|---|"]
        base = scaling[0]["runs"] / scaling[0]["wall_seconds"]
        for s in scaling:
            r = s["runs"] / s["wall_seconds"]
            lines.append(f"| {s['workers']} | {s['runs']} | {s['wall_seconds']:.2f} | {r:.1f} | {r / base:.2f} |")
        lines.append("")
    path = store.out / "study.md"
    tmp = store.out / "study.md.tmp"
    tmp.write_text("\n".join(lines) + "\n")
    tmp.replace(path)
    return path
