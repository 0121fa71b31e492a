#!/usr/bin/env python3
"""Figures of `medspring accuracy` (docs/accuracy.md): reads DIR/accuracy.json and DIR/error_maps.json and
writes DIR/figures/speed_accuracy.png, DIR/figures/error_<organ>_<params>.png and
DIR/figures/force_displacement_<organ>.png and DIR/figures/force_indentation_<organ>.png (matplotlib, Agg)."""
import json
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


def speed_accuracy(acc, out):
    fig, ax = plt.subplots(figsize=(8, 5))
    kinds = sorted({r["kind"] for o in acc["organs"] for r in o["models"]})
    colour = {k: "C%d" % (i % 10) for i, k in enumerate(kinds)}
    organ_marker = {}
    for i, organ in enumerate(acc["organs"]):
        organ_marker[organ["organ"]] = "os^D"[i % 4]
        for r in organ["models"]:
            ax.scatter([r["update_us"]], [r["held_out_mean_rms_pct"]], marker=organ_marker[organ["organ"]], s=40,
                       facecolors=colour[r["kind"]] if r["calibrated"] else "none", edgecolors=colour[r["kind"]])
        fem_us = organ["fem"]["median_solve_s"] * 1e6
        ax.axvline(fem_us, color="k", ls="--", lw=0.8)
        ax.annotate("FEM solve\n%s" % organ["organ"], (fem_us, 0.02 + 0.12 * i), xycoords=("data", "axes fraction"),
                    fontsize=7, ha="right")
    # the vessel: SMRM rows, y = mean held-out lumen RMS error in % of the FEM loaded-atom displacement
    vkinds = sorted({r["kind"] for v in acc.get("vessels", []) for r in v["models"]})
    for k in vkinds:
        colour[k] = "C%d" % (len(colour) % 10)
    kinds = kinds + vkinds
    for i, v in enumerate(acc.get("vessels", [])):
        organ_marker[v["vessel"]] = "v<>p"[i % 4]
        for r in v["models"]:
            held = [c["lumen_rms_pct"] for c in r["cases"] if "lumen_rms_pct" in c and not c["train"]]
            if held:
                ax.scatter([r["update_us"]], [sum(held) / len(held)], marker=organ_marker[v["vessel"]], s=40,
                           facecolors=colour[r["kind"]] if r["calibrated"] else "none", edgecolors=colour[r["kind"]])
        fem_us = v["fem"]["median_solve_s"] * 1e6
        ax.axvline(fem_us, color="k", ls=":", lw=0.8)
        ax.annotate("FEM solve\n%s" % v["vessel"], (fem_us, 0.9 - 0.12 * i), xycoords=("data", "axes fraction"),
                    fontsize=7, ha="right")
    handles = [plt.Line2D([], [], color=colour[k], marker="o", ls="", label=k) for k in kinds]
    handles += [plt.Line2D([], [], color="k", marker=m, ls="", mfc="none", label=o) for o, m in organ_marker.items()]
    ax.legend(handles=handles, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)  # below the axes
    ax.set_xscale("log")
    ax.set_xlabel("time per update (us, median; dashed: one CalculiX static solve)")
    ax.set_ylabel("RMS surface error, % of FEM contact displacement\n(mean over held-out cases)")
    ax.set_title("Speed against accuracy (open: default parameters, filled: calibrated)")
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def force_displacement(organ, out):
    """Contact displacement against force at every site: the FEM (black) and each model kind (colour; dashed:
    default parameters, solid: calibrated). Returns the number of curves drawn."""
    sites = sorted({c["site"] for r in organ["models"] for c in r["cases"]})
    kinds = sorted({r["kind"] for r in organ["models"]})
    colour = {k: "C%d" % (i % 10) for i, k in enumerate(kinds)}
    fig, axes = plt.subplots(1, len(sites), figsize=(3.2 * len(sites), 3.6), squeeze=False, sharey=True)
    drawn = 0
    for ax, site in zip(axes[0], sites):
        fem = {}
        for r in organ["models"]:
            pts = sorted((c["force_N"], c["contact_model_mm"]) for c in r["cases"]
                         if c["site"] == site and "contact_model_mm" in c)
            for c in r["cases"]:
                if c["site"] == site and "contact_fem_mm" in c:
                    fem[c["force_N"]] = c["contact_fem_mm"]
            if pts:
                f, u = zip(*pts)
                ax.plot(f, u, "-" if r["calibrated"] else "--", color=colour[r["kind"]], marker=".", lw=1)
                drawn += 1
        if fem:
            f = sorted(fem)
            ax.plot([0.0] + f, [0.0] + [fem[x] for x in f], "k-o", lw=2, ms=4)
            drawn += 1
        ax.set_title("site %d" % site, fontsize=9)
        ax.set_xlabel("force (N)")
        ax.grid(True, alpha=0.3)
    axes[0][0].set_ylabel("contact displacement (mm)")
    handles = [plt.Line2D([], [], color="k", lw=2, label="FEM (CalculiX)")]
    handles += [plt.Line2D([], [], color=colour[k], label=k) for k in kinds]
    handles += [plt.Line2D([], [], color="grey", ls="--", label="default"),
                plt.Line2D([], [], color="grey", ls="-", label="calibrated")]
    fig.legend(handles=handles, fontsize=6, loc="upper right", ncol=2)
    fig.suptitle("Force against contact displacement: %s" % organ["organ"], fontsize=10, x=0.3)
    fig.tight_layout(rect=(0, 0, 1, 0.8))
    fig.savefig(out, dpi=130)
    plt.close(fig)
    return drawn


def force_indentation(organ, out):
    """Force against indentation depth of a rigid sphere (issue 18): the FEM (black), the Hertz-like estimate
    (grey dotted) and MedSpring's sphere tool on each model (dashed: default, solid: calibrated)."""
    depth = organ["depths_mm"]
    fig, ax = plt.subplots(figsize=(5.5, 4))
    ax.plot([0.0] + depth, [0.0] + [p["force_N"] for p in organ["fem"]["points"]], "k-o", lw=2, ms=4,
            label="FEM (CalculiX, rigid sphere)")
    if organ["hertz_N"]:
        ax.plot([0.0] + depth, [0.0] + organ["hertz_N"], color="grey", ls=":", label="Hertz, local curvature")
    for i, m in enumerate(organ["models"]):
        ax.plot([0.0] + depth, [0.0] + [p["force_N"] for p in m["points"]], "-" if m["calibrated"] else "--",
                color="C%d" % i, marker=".",
                label="MedSpring %s, %s" % (m["kind"], "calibrated" if m["calibrated"] else "default"))
    ax.set_xlabel("indentation depth (mm)")
    ax.set_ylabel("force on the sphere (N)")
    ax.set_title("Sphere R = %g mm on the %s" % (organ["radius_mm"], organ["organ"]), fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def error_map(m, out):
    V = np.array(m["V"]).reshape(-1, 3)
    F = np.array(m["F"]).reshape(-1, 3)
    e = np.array(m["error_mm"])
    fig = plt.figure(figsize=(7, 5))
    ax = fig.add_subplot(111, projection="3d")
    face_err = e[F].mean(axis=1)
    norm = plt.Normalize(0, max(face_err.max(), 1e-9))
    cmap = plt.get_cmap("viridis")
    poly = Poly3DCollection(V[F], facecolors=cmap(norm(face_err)), edgecolors="none")
    ax.add_collection3d(poly)
    lo, hi = V.min(axis=0), V.max(axis=0)
    c, r = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.view_init(elev=35, azim=-60)
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=norm)
    fig.colorbar(sm, ax=ax, shrink=0.7, label="|u_model - u_FEM| (mm)")
    ax.set_title(m["title"], fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def vessel_force_displacement(v, out):
    """Loaded-atom displacement against the force, per site: FEM (black) and the SMRM parameter sets."""
    atoms = sorted({c["atom"] for r in v["models"] for c in r["cases"]})
    fig, axes = plt.subplots(1, len(atoms), figsize=(3.2 * len(atoms), 3.2), squeeze=False)
    style = {"default": ":", "material": "--", "calibrated": "-"}
    for ax, a in zip(axes[0], atoms):
        fem = {}
        for r in v["models"]:
            pts = sorted((c["force_N"], c["loaded_model_mm"]) for c in r["cases"] if c["atom"] == a and "loaded_model_mm" in c)
            for c in r["cases"]:
                if c["atom"] == a and "loaded_fem_mm" in c:
                    fem[c["force_N"]] = c["loaded_fem_mm"]
            if pts:
                ax.plot([0] + [p[0] for p in pts], [0] + [p[1] for p in pts], style.get(r["params"], "-"),
                        color="C0" if r["nonlinear"] else "C1", lw=1, label="%s, %s" % (r["kind"], r["params"]))
        f = sorted(fem)
        ax.plot([0] + f, [0] + [fem[x] for x in f], "k-o", ms=3, lw=1.5, label="FEM wall (mid-surface)")
        ax.set_title("atom %d" % a, fontsize=9)
        ax.set_xlabel("force (N)")
        ax.grid(True, alpha=0.3)
    axes[0][0].set_ylabel("loaded-atom displacement (mm)")
    axes[0][-1].legend(fontsize=6)
    fig.suptitle("%s: SMRM centerline against the FEM wall" % v["vessel"], fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def main():
    d = pathlib.Path(sys.argv[1])
    acc = json.loads((d / "accuracy.json").read_text())
    maps = json.loads((d / "error_maps.json").read_text())
    (d / "figures").mkdir(exist_ok=True)
    if acc["organs"]:
        speed_accuracy(acc, d / "figures" / "speed_accuracy.png")
    for organ in acc["organs"]:
        force_displacement(organ, d / "figures" / ("force_displacement_" + organ["organ"].replace(" ", "_") + ".png"))
    for v in acc.get("vessels", []):
        vessel_force_displacement(v, d / "figures" / ("force_displacement_" + v["vessel"].split(" ")[0] + ".png"))
    for organ in acc.get("indentation", {}).get("organs", []):
        force_indentation(organ, d / "figures" / ("force_indentation_" + organ["organ"].replace(" ", "_") + ".png"))
    for name, m in maps.items():
        error_map(m, d / "figures" / ("error_" + name.replace(" ", "_") + ".png"))


if __name__ == "__main__":
    main()
