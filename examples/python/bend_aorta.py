#!/usr/bin/env python3
"""Bend the real aorta: the SMRM vessel model built from the VMR 0159 aorta centerline.

The centerline (vmr-0159-aorta-centerline.vtp, VMTK output in centimetres with the lumen radius per
point) is read and scaled to mm; its longest branch (345 mm) becomes a simplified-medial-representation
vessel (§5): 40 centerline atoms in a Duffing chain with both ends fixed, 30 spokes per atom of the
local radius, the surface rebuilt every update from rotation-minimising frames (D-12). The paper's
vessel experiment (§7.2, Fig. 10) then pushes atom 20 with a light (0.05 N) and a strong (0.5 N)
force, linear and nonlinear chain, held to 500 ms and released.

A second run with `Simulation` adds the local deformation of eq. (6) under the tool and writes the
bent surface (with its displacement) as VTK PolyData for ParaView.

Data: $MEDSPRING_DATA or ../shared/data beside the repository.

    /usr/bin/python3 examples/python/bend_aorta.py --out out/python
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

import medspring as ms

CENTERLINE = "vmr-0159-aorta-centerline.vtp"


def data_file(name: str) -> Path:
    """$MEDSPRING_DATA/name, else ../shared/data/name beside the repository."""
    folder = os.environ.get("MEDSPRING_DATA") or Path(__file__).resolve().parents[2].parent / "shared" / "data"
    path = Path(folder) / name
    if not path.is_file():
        raise SystemExit(f"data file {name} not found in {folder} (set MEDSPRING_DATA)")
    return path


def aorta_vessel(path: Path, line: int = 2, atoms: int = 40) -> ms.SmrmVessel:
    """The SMRM vessel of one centerline branch (the file is in cm)."""
    lines = ms.read_centerlines(path, unit="cm")
    return ms.smrm_from_centerline(lines[line], ms.SmrmSettings(atoms=atoms))


def experiment(vessel: ms.SmrmVessel, atom: int = 20, t_end: float = 1000.0) -> ms.VesselExperimentResult:
    """The four runs of §7.2 (light / strong force, linear / nonlinear chain)."""
    return ms.run_vessel_experiment(vessel, ms.VesselExperimentSettings(atom=atom, t_end=t_end))


def bend_with_local_overlay(vessel: ms.SmrmVessel, atom: int, direction, force: float = 0.5,
                            t_hold: float = 500.0) -> ms.Simulation:
    """Simulation with the local patch solve on: `force` N on the contact node of `atom`, held."""
    settings = ms.SimulationSettings(local=ms.LocalOptions(enabled=True))
    sim = ms.Simulation(vessel, settings)
    F = force * np.asarray(direction, float)
    node = vessel.contact_node(atom, F)
    sim.set_loads([ms.PointLoad(node=node, force=F, t_ramp=20.0)])
    sim.update(nsteps=int(round(t_hold / settings.step.dt)))
    return sim


def plot(vessel: ms.SmrmVessel, result: ms.VesselExperimentResult, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(12, 5.5))
    ax = fig.add_subplot(1, 2, 1)
    # view plane: the force direction d (horizontal) and the main axis of the rest centerline made
    # orthogonal to d (vertical); true scale
    C0 = vessel.rest_atoms
    run = result.strong_nonlinear
    C = C0 + run.profile
    d = result.direction / np.linalg.norm(result.direction)
    axis = np.linalg.svd(C0 - C0.mean(axis=0))[2][0]
    e = axis - (axis @ d) * d
    e /= np.linalg.norm(e)
    o = C0.mean(axis=0)

    def view(P):
        return (P - o) @ d, (P - o) @ e

    ax.scatter(*view(vessel.rest_surface), s=1, c="lightgray", label="rest surface")
    ax.scatter(*view(run.surface), s=1, c="salmon", alpha=0.5, label="surface at release")
    ax.plot(*view(C0), "k.-", lw=1, ms=3, label="rest centerline")
    ax.plot(*view(C), "r.-", lw=1.5, ms=3, label=f"bent by {run.force} N (nonlinear chain)")
    ax.annotate("F", xy=view(C0[result.atom]), xytext=(-25, 0), textcoords="offset points",
                arrowprops={"arrowstyle": "->"})
    ax.set_aspect("equal")
    ax.set_xlabel("along the force (mm)")
    ax.set_ylabel("along the vessel (mm)")
    ax.set_title(f"aorta SMRM, atom {result.atom} pushed")
    ax.legend(fontsize=7, loc="lower left", markerscale=3)
    b = fig.add_subplot(1, 2, 2)
    for name in ("light_linear", "light_nonlinear", "strong_linear", "strong_nonlinear"):
        r = getattr(result, name)
        b.plot(r.time, r.atom_displacement, ls="--" if "linear" == name.split("_")[1] else "-",
               label=f"{r.force} N, {'nonlinear' if r.nonlinear else 'linear'} chain")
    b.axvline(500, color="gray", lw=0.8, ls=":")
    b.set_xlabel("time (ms)")
    b.set_ylabel(f"|displacement| of atom {result.atom} (mm)")
    b.set_title("force on, hold, release (§7.2)")
    b.grid(alpha=0.3)
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("out/python"), help="folder for the PNG and VTP")
    ap.add_argument("--line", type=int, default=2, help="centerline branch (2: the longest, 345 mm)")
    args = ap.parse_args(argv)
    vessel = aorta_vessel(data_file(CENTERLINE), args.line)
    report = vessel.report
    print(f"aorta branch {args.line}: {vessel.num_atoms} atoms, {vessel.num_surface_nodes} surface nodes, "
          f"radius {vessel.atom_radius.min():.1f}-{vessel.atom_radius.max():.1f} mm; "
          + ("; ".join(report.notes) or "no notes"))
    result = experiment(vessel)
    for name in ("light_linear", "light_nonlinear", "strong_linear", "strong_nonlinear"):
        r = getattr(result, name)
        print(f"{name:17} {r.force:5.2f} N: atom {r.atom_hold:7.3f} mm, contact node {r.contact_hold:7.3f} mm at "
              f"release, back at rest {r.return_time:.1f} ms later, warnings {r.warnings}")
    args.out.mkdir(parents=True, exist_ok=True)
    png = args.out / "bend_aorta.png"
    plot(vessel, result, png)
    print(f"wrote {png}")
    sim = bend_with_local_overlay(vessel, result.atom, -result.direction)
    dent = np.linalg.norm(sim.local_displacement, axis=1).max()
    print(f"with local deformation: contact node {sim.loads[0].node}, local dent {dent:.3f} mm on "
          f"{len(sim.local_nodes)} patch nodes")
    if ms.has_io:
        vtp = args.out / "bend_aorta.vtp"
        U = sim.displacement()
        ms.write_vtp(vtp, ms.SurfaceMesh(np.array(sim.surface), vessel.faces),
                     {"displacement": U, "magnitude": np.linalg.norm(U, axis=1)})
        print(f"wrote {vtp}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
