#!/usr/bin/env python3
"""Poke the real kidney and plot force-displacement for linear vs nonlinear springs.

The kidney is the Visible Human Male left kidney (kidney_left_hubmap_vhm.obj, 5,002 vertices, stored
in metres and scaled to mm on load) simulated as a surface mass-spring body (SurfaceBody: one spring
per edge, return springs, kidney parameters of ALGORITHMS.md §9) -- once with linear springs and once
with Duffing springs (Strain rule k' = k / L0^2, D-3). The hybrid kidney (surface + skeleton) of the
real organ needs the balloon surface and skeleton of the meshing/skeleton layers; the phantom version
is `medspring.hybrid_kidney_phantom()`.

Two experiments on the most lateral vertex, pushed along its inward normal:
  1. quasi-static force-displacement curve (static equilibrium at every force level, §2.4);
  2. the dynamic press of §7.1: 1 N ramped over 20 ms, held to 500 ms, released, run to 1000 ms.

Data: $MEDSPRING_DATA or ../shared/data beside the repository.

    /usr/bin/python3 examples/python/poke_kidney.py --out out/python
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

import medspring as ms

KIDNEY = "kidney_left_hubmap_vhm.obj"


def data_file(name: str) -> Path:
    """$MEDSPRING_DATA/name, else ../shared/data/name beside the repository."""
    folder = os.environ.get("MEDSPRING_DATA") or Path(__file__).resolve().parents[2].parent / "shared" / "data"
    path = Path(folder) / name
    if not path.is_file():
        raise SystemExit(f"data file {name} not found in {folder} (set MEDSPRING_DATA)")
    return path


def kidney_bodies(mesh: ms.SurfaceMesh) -> dict:
    """The surface mass-spring kidney with linear and with Duffing springs (otherwise identical)."""
    bodies = {}
    for label, mode in (("linear", "linear"), ("nonlinear", "strain")):
        params = ms.SurfaceBodyParams(duffing=ms.DuffingSettings(mode=mode))
        bodies[label] = ms.SurfaceBody(mesh, params, f"kidney ({label})")
    return bodies


def poke_node(mesh: ms.SurfaceMesh) -> tuple[int, np.ndarray]:
    """The most lateral vertex (largest x) and its inward unit normal."""
    node = int(np.argmax(mesh.V[:, 0]))
    return node, -ms.vertex_normals(mesh)[node]


def force_displacement(bodies: dict, node: int, direction, forces) -> dict:
    """Static displacement (mm) of the poked node along the force for every force level (N)."""
    return {label: ms.static_force_displacement(body, node, direction, forces) for label, body in bodies.items()}


def press(bodies: dict, node: int, direction, force: float = 1.0, t_end: float = 1000.0) -> dict:
    """The press-and-release experiment of §7.1 for every body: dict of time series."""
    F = force * np.asarray(direction)
    return {label: ms.press_release(body, node, F, t_ramp=20, t_release=500, t_end=t_end) for label, body in
            bodies.items()}


def plot(forces, curves: dict, runs: dict, path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.5))
    for label, u in curves.items():
        a.plot(np.r_[0.0, u], np.r_[0.0, forces], "o-", ms=4, label=f"{label} springs")
    a.set_xlabel("displacement of the poked node (mm)")
    a.set_ylabel("force (N)")
    a.set_title("quasi-static poke")
    a.grid(alpha=0.3)
    a.legend()
    for label, run in runs.items():
        b.plot(run["time"], run["contact"], label=f"{label} springs")
    b.axvline(500, color="gray", lw=0.8, ls=":")
    b.set_xlabel("time (ms)")
    b.set_ylabel("|displacement| of the poked node (mm)")
    b.set_title("press 1 N, release at 500 ms")
    b.grid(alpha=0.3)
    b.legend()
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("out/python"), help="folder for the PNG")
    ap.add_argument("--max-force", type=float, default=1.0, help="largest poke force, N")
    ap.add_argument("--levels", type=int, default=8, help="force levels of the static curve")
    args = ap.parse_args(argv)
    mesh = ms.read_mesh(data_file(KIDNEY), unit="m")
    print(f"{KIDNEY}: {mesh.validate().summary()}")
    bodies = kidney_bodies(mesh)
    node, direction = poke_node(mesh)
    print(f"poking node {node} at {np.round(mesh.V[node], 2)} mm along {np.round(direction, 3)}")
    forces = np.linspace(args.max_force / args.levels, args.max_force, args.levels)
    curves = force_displacement(bodies, node, direction, forces)
    print(f"{'force (N)':>10}" + "".join(f"{label + ' (mm)':>16}" for label in curves))
    for i, f in enumerate(forces):
        print(f"{f:10.3f}" + "".join(f"{curves[label][i]:16.3f}" for label in curves))
    runs = press(bodies, node, direction, force=args.max_force)
    for label, run in runs.items():
        hold = run["contact"][np.searchsorted(run["time"], 500.0)]
        back = run["time"][(run["time"] > 500) & (run["max_displacement"] < 1e-3)]
        print(f"press {label}: {hold:.3f} mm at 500 ms, back within 1e-3 mm "
              + (f"{back[0] - 500:.1f} ms after release" if back.size else "not by 1000 ms")
              + f", warnings {run['sim'].state.warnings.total()}")
    args.out.mkdir(parents=True, exist_ok=True)
    png = args.out / "poke_kidney.png"
    plot(forces, curves, runs, png, f"Real kidney (VHM, {mesh.num_vertices} nodes): linear vs Duffing springs")
    print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
