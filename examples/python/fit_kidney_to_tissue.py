#!/usr/bin/env python3
"""Fit the hybrid kidney phantom to a tissue of Young's modulus E (docs/accuracy.md).

The FEM reference is CalculiX (compressible Neo-Hookean, NLGEOM) on quadratic tetrahedra of the
phantom's own closed surface; both models hold the same posterior support (the nodes within 7 mm of the
most posterior point) and receive the same load: a force spread uniformly over a contact disk of radius
8 mm on the anterior surface. medspring.calibrate fits k_surf, k_spoke, k_cl and k_r on two training sites
at 0.5 N; the fitted model is then checked on a site and forces it never saw.

Needs ccx (Debian calculix-ccx) and tetgen. Units: mm, N, kPa for E.

    /usr/bin/python3 examples/python/fit_kidney_to_tissue.py --E-kPa 10
    /usr/bin/python3 examples/python/fit_kidney_to_tissue.py --workers 2     # FEM solves as Dask tasks
    /usr/bin/python3 examples/python/fit_kidney_to_tissue.py --scheduler tcp://HOST:8786

With --workers N (a LocalCluster) or --scheduler, the four CalculiX solves (two training, two held-out)
run in parallel through medspring.study.fem (docs/studies.md); the results are the same bit for bit.
"""

from __future__ import annotations

import argparse

import numpy as np

import medspring as ms

SUPPORT = dict(support_direction=(0.0, 0.0, -1.0), support_depth=7.0)


def anterior_site(V: np.ndarray, x: float) -> np.ndarray:
    """The most anterior (+z) vertex among those within 8 mm of x along the long axis."""
    near = np.abs(V[:, 0] - x) < 8.0
    i = np.flatnonzero(near)[np.argmax(V[near, 2])]
    return V[i]


def run(E_kPa: float = 10.0, nu: float = 0.45, workers: int | None = None, scheduler: str | None = None) -> dict:
    phantom = ms.hybrid_kidney_phantom()
    V, F = np.array(phantom.rest_surface), np.array(phantom.faces)
    atoms = ms.kidney_phantom_atoms()
    train = np.array([anterior_site(V, -25.0), anterior_site(V, 25.0)])
    push = np.array([0.0, 0.0, -0.5])  # 0.5 N towards the support
    if workers is not None or scheduler is not None:
        from medspring.study import fem

        held = [{"centre": anterior_site(V, 0.0), "force": (0.0, 0.0, -f)} for f in (0.2, 1.0)]
        r = fem.calibrate(V, F, atoms, train, np.tile(push, (2, 1)), held_out=held, E_kPa=E_kPa, nu=nu,
                          workers=workers, scheduler=scheduler, **SUPPORT)
        rows = [dict(force=-float(h["force"][2]), **{k: h.get(k, float("nan")) for k in
                     ("contact_fem", "contact_model", "contact_error", "rms_error")}) for h in r["held_out"]]
        return dict(parameters=r["parameters"], held_out=rows)
    fit = ms.calibrate(V, F, atoms, train, np.tile(push, (2, 1)), E_kPa=E_kPa, nu=nu, **SUPPORT)

    settings = ms.HybridSettings()
    settings.k_surf, settings.k_spoke, settings.k_cl = fit["k_surf"], fit["k_spoke"], fit["k_cl"]
    settings.surface_node.return_k = fit["k_r"]
    settings.atom_node.return_k = fit["k_r"]
    settings.fixed = list(fit["support"])
    model = ms.HybridKidney(ms.SurfaceMesh(V, F), atoms, settings)

    held_out = anterior_site(V, 0.0)  # a site the fit never saw
    contact = int(np.argmin(np.linalg.norm(V - held_out, axis=1)))
    rows = []
    for f in (0.2, 1.0):  # forces the fit never saw
        force = np.array([0.0, 0.0, -f])
        u_fem = ms.fem_reference(V, F, held_out, force, E_kPa=E_kPa, nu=nu, **SUPPORT)["displacement"]
        u = ms.spring_displacement(model, held_out, force)
        c_fem = np.linalg.norm(u_fem[contact])
        rows.append(dict(force=f, contact_fem=c_fem, contact_model=np.linalg.norm(u[contact]),
                         contact_error=np.linalg.norm(u[contact] - u_fem[contact]) / c_fem,
                         rms_error=np.sqrt(np.mean(np.sum((u - u_fem) ** 2, axis=1))) / c_fem))
    return dict(parameters=fit, held_out=rows)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--E-kPa", type=float, default=10.0)
    p.add_argument("--nu", type=float, default=0.45)
    p.add_argument("--workers", type=int, default=None, help="solve the FEM cases on a LocalCluster of N processes")
    p.add_argument("--scheduler", default=None, help="solve the FEM cases on this Dask cluster (tcp://HOST:PORT)")
    a = p.parse_args()
    r = run(a.E_kPa, a.nu, a.workers, a.scheduler)
    print("fitted (N/mm): " + ", ".join(f"{k} = {r['parameters'][k]:.4g}" for k in ("k_surf", "k_spoke", "k_cl", "k_r")))
    for row in r["held_out"]:
        print(f"held-out site, {row['force']} N: contact FEM {row['contact_fem']:.2f} mm, model "
              f"{row['contact_model']:.2f} mm ({100 * row['contact_error']:.1f} %), RMS surface error "
              f"{100 * row['rms_error']:.1f} % of the FEM contact displacement")


if __name__ == "__main__":
    main()
