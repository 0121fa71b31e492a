#!/usr/bin/env python3
"""Plots of `medspring paper` (matplotlib, Agg backend; no display needed).

usage: plots.py PLOTS.json

PLOTS.json = {
  "out_dir": folder for the PNGs,
  "kidney": [run, ...], "vessel": [run, ...]   run = {"dir": scene output folder (trace.csv,
      summary.json, optional static_curve.csv and atoms frames), "label", "force" (N), "nonlinear", "local"},
  "hold_time": ms at which the force is held (profiles),
  "tables": {"cases": [{"name", "model", "nonlinear", "local", "median_us", "mean_us"}], "paper": {...}},
  "title_suffix": text added to every title (e.g. "phantoms")
}
Writes fig9_displacement.png, fig10_displacement.png, force_displacement.png, vessel_profile.png,
timing.png into out_dir.
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLORS = {0.2: "tab:orange", 1.0: "tab:blue", 0.05: "tab:orange", 0.5: "tab:blue"}


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    head, body = rows[0], rows[1:]
    return {h: [float(r[i]) for r in body] for i, h in enumerate(head)}


def summary(run):
    with open(os.path.join(run["dir"], "summary.json")) as f:
        return json.load(f)


def contact_column(trace, s):
    return f"node_{s['trace_nodes'][0]}_mm"


def style(run):
    return dict(color=COLORS.get(run["force"], "tab:green"), linestyle="-" if run["nonlinear"] else "--",
                linewidth=1.6 if run["nonlinear"] else 1.3)


def fig9(spec, out):
    runs = spec["kidney"]
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for r in runs:
        s = summary(r)
        t = read_csv(os.path.join(r["dir"], "trace.csv"))
        c = contact_column(t, s)
        a.plot(t["time_ms"], t[c], label=f"{r['label']}: contact node", **style(r))
        atom_cols = [k for k in t if k.startswith("atom_")]
        if atom_cols and r["nonlinear"]:
            a.plot(t["time_ms"], t[atom_cols[0]], color=style(r)["color"], linestyle=":", linewidth=1.2,
                   label=f"{r['label']}: middle atom {atom_cols[0][5:-3]}")
        rel = s.get("release_ms") or 500.0
        tt = [x - rel for x in t["time_ms"] if x >= rel - 10]
        mm = [m for x, m in zip(t["time_ms"], t["max_disp_mm"]) if x >= rel - 10]
        b.semilogy(tt, [max(m, 1e-9) for m in mm], label=r["label"], **style(r))
    a.set_xlabel("time (ms)")
    a.set_ylabel("displacement |u| (mm)")
    a.set_title("Kidney: force on, held, released at 500 ms" + spec.get("title_suffix", ""))
    a.legend(fontsize=7.5)
    a.grid(alpha=0.3)
    b.axhline(1e-3, color="k", linewidth=0.8, linestyle=":")
    b.text(150, 1.3e-3, "1e-3 mm", fontsize=8)
    b.set_xlim(-10, 250)
    b.set_xlabel("time after release (ms)")
    b.set_ylabel("max surface displacement (mm)")
    b.set_title("Kidney: back to rest after release")
    b.legend(fontsize=8)
    b.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig9_displacement.png"), dpi=110)
    plt.close(fig)


def fig10(spec, out):
    runs = spec["vessel"]
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for r in runs:
        s = summary(r)
        t = read_csv(os.path.join(r["dir"], "trace.csv"))
        c = contact_column(t, s)
        if not r.get("local"):
            a.plot(t["time_ms"], t[c], label=f"{r['label']}", **style(r))
        elif r["nonlinear"]:  # the linear runs coincide with these within the line width
            b.plot(t["time_ms"], t["local_contact_mm"], label=f"{r['label']}: local |U_c|", **style(r))
            b.plot(t["time_ms"], t[c], color=style(r)["color"], linestyle=":", linewidth=1.2,
                   label=f"{r['label']}: contact, global + local")
    a.set_xlabel("time (ms)")
    a.set_ylabel("contact node |u| (mm)")
    a.set_title("Vessel (global only): light vs strong, linear vs nonlinear" + spec.get("title_suffix", ""),
                fontsize=10)
    a.legend(fontsize=8)
    a.grid(alpha=0.3)
    b.set_xlabel("time (ms)")
    b.set_ylabel("displacement (mm)")
    b.set_title("Vessel with local deformation (eq. 6)", fontsize=10)
    b.legend(fontsize=7.5)
    b.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig10_displacement.png"), dpi=110)
    plt.close(fig)


def atom_profile(run, hold):
    """|u| of every atom at the recorded frame nearest to `hold` (from the atoms .vtp)."""
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy

    s = summary(run)
    frames = [f for f in s["frames"] if "atoms_file" in f]
    if not frames:
        return None
    f = min(frames, key=lambda f: abs(f["time_ms"] - hold))
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(os.path.join(run["dir"], f["atoms_file"]))
    r.Update()
    return vtk_to_numpy(r.GetOutput().GetPointData().GetArray("displacement_magnitude"))


def vessel_profile(spec, out):
    fig, a = plt.subplots(figsize=(6.5, 4.2))
    for r in spec["vessel"]:
        if r.get("local"):
            continue
        p = atom_profile(r, spec.get("hold_time", 500.0))
        if p is None:
            continue
        a.plot(range(len(p)), p, marker="o", markersize=2.5, label=r["label"], **style(r))
    a.set_xlabel("atom index")
    a.set_ylabel("atom displacement |u| (mm)")
    a.set_title(f"Vessel centerline at t = {spec.get('hold_time', 500):g} ms (force on atom 20)"
                + spec.get("title_suffix", ""), fontsize=10)
    a.legend(fontsize=8)
    a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "vessel_profile.png"), dpi=110)
    plt.close(fig)


def force_displacement(spec, out):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, key, title in ((axes[0], "kidney", "Kidney"), (axes[1], "vessel", "Vessel (global)")):
        for r in spec[key]:
            if r.get("local"):
                continue
            path = os.path.join(r["dir"], "static_curve.csv")
            if os.path.exists(path):
                c = read_csv(path)
                ax.plot(c["contact_mm"], c["force_N"], label=f"static, {'nonlinear' if r['nonlinear'] else 'linear'}",
                        color="k" if r["nonlinear"] else "0.5", linestyle="-" if r["nonlinear"] else "--")
            s = summary(r)
            ax.plot([s["contact_hold_mm"]], [r["force"]], marker="o" if r["nonlinear"] else "s", linestyle="none",
                    color=style(r)["color"], label=f"dynamic, force held: {r['label']}")
        ax.set_xlabel("contact node displacement (mm)")
        ax.set_ylabel("force (N)")
        ax.set_title(f"{title}: force-displacement" + spec.get("title_suffix", ""), fontsize=10)
        ax.legend(fontsize=7.5)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "force_displacement.png"), dpi=110)
    plt.close(fig)


def timing(spec, out):
    tables = spec["tables"]
    cases = {(c["model"], c["nonlinear"], c["local"]): c for c in tables["cases"]}
    paper = tables["paper"]
    groups = [("Table I\nlinear", False, "off"), ("Table I / II\nnonlinear", True, "off"),
              ("Table II\nwith local\n(no cache)", True, "no_cache"), ("with local\n(cached factor)", True, "cache")]
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    width = 0.27
    for k, model in enumerate(["MS", "SMRM", "kidney MS"]):
        xs, ys = [], []
        for g, (_, nl, loc) in enumerate(groups):
            c = cases.get((model, nl, loc))
            if c:
                xs.append(g + (k - 1) * width)
                ys.append(c["median_us"])
        bars = a.bar(xs, ys, width, label={"MS": "mass-spring (vessel, 1240 masses)", "SMRM": "SMRM (40 atoms + 1200)",
                                           "kidney MS": "kidney hybrid (458 + 42)"}[model])
        a.bar_label(bars, fmt="%.1f", fontsize=7)
    a.set_xticks(range(len(groups)))
    a.set_xticklabels([g[0] for g in groups], fontsize=8)
    a.set_ylabel("median time per update (µs)")
    a.set_ylim(0, a.get_ylim()[1] * 1.3)
    a.set_title("Measured here (D-18: warm-up, then timed updates)", fontsize=10)
    a.legend(fontsize=8, loc="upper left", ncol=2)
    a.grid(alpha=0.3, axis="y")
    pg = [("Table I\nlinear", "linear"), ("Table I / II\nnonlinear", "nonlinear"), ("Table II\nwith local", "local")]
    for k, model in enumerate(["MS", "SMRM"]):
        ys = [paper[model][key] for _, key in pg]
        bars = b.bar([g + (k - 0.5) * width for g in range(len(pg))], ys, width,
                     label={"MS": "Mass-Spring", "SMRM": "Simplified M-rep"}[model])
        b.bar_label(bars, fmt="%.0f", fontsize=8)
    b.set_xticks(range(len(pg)))
    b.set_xticklabels([g[0] for g in pg], fontsize=8)
    b.set_ylabel("time per update (ms)")
    b.set_title("The paper (Pentium IV 2.6 GHz, 2007)", fontsize=10)
    b.legend(fontsize=8)
    b.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "timing.png"), dpi=110)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1]) as f:
        spec = json.load(f)
    out = spec["out_dir"]
    os.makedirs(out, exist_ok=True)
    for fn in (fig9, fig10, vessel_profile, force_displacement, timing):
        fn(spec, out)
        print(f"plotted {fn.__name__}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
