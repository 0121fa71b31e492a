"""medspring.calibrate's site read-out, training forces and site weight (docs/accuracy-calibration.md, "From
Python"): site_readout='node'|'disk-mean', train_forces=[...] and site_weight=W follow the rules of `medspring
calibrate --site-readout --train-force --site-weight` (one declaration each: fem::SiteReadout,
fem::checked_train_forces, fem::checked_site_weight), the
train_forces loads are the force rows rescaled, and the disk-mean fit reads the FEM's disk mean. The fits
run on a coarse sphere (162 vertices, about 1 s per CalculiX solve); needs ccx and tetgen."""

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import medspring as ms

pytestmark = pytest.mark.skipif(
    not getattr(ms, "has_fem", False) or shutil.which("ccx") is None or shutil.which("tetgen") is None,
    reason="needs the fem layer, ccx and tetgen")

KW = dict(support_direction=(0, 0, -1), support_depth=3.0, radius=4.0, E_kPa=10.0)
ATOMS = np.array([[-4.0, 0, 0], [0, 0, 0], [4.0, 0, 0]])
EXE = Path(ms.__file__).resolve().parents[1].parent / "apps" / "medspring"


def sphere():
    s = ms.icosphere(2, 10.0)
    return np.array(s.V), np.array(s.F)


def test_bad_site_readout_and_training_forces_are_refused_with_the_clis_words():
    V, F = sphere()
    top = V[np.argmax(V[:, 2])][None, :]
    down = np.array([[0.0, 0.0, -0.02]])
    cases = [  # (keywords, the rule's words: the same text the CLI prints after its option's name)
        (dict(site_readout="centre"), "must be node or disk-mean (got 'centre')"),
        (dict(site_readout="Node"), "must be node or disk-mean (got 'Node')"),
        (dict(train_forces=[0.2, -1.0]), "must be > 0 N or a list of such (got '-1')"),
        (dict(train_forces=0.0), "must be > 0 N or a list of such (got '0')"),
        (dict(train_forces=[0.2, float("nan")]), "must be > 0 N or a list of such (got 'nan')"),
        (dict(train_forces=[]), "must list at least one force"),
        (dict(site_weight=-1.0), "must be a number >= 0 (got '-1')"),
        (dict(site_weight=float("inf")), "must be a number >= 0 (got 'inf')"),
    ]
    for kw, words in cases:
        name = next(iter(kw))
        with pytest.raises(ms.InvalidInput) as e:
            ms.calibrate(V, F, ATOMS, top, down, **kw, **KW)
        assert str(e.value) == f"calibrate: {name} {words}", kw
    with pytest.raises(ms.InvalidInput, match="train_forces must be a force in N or a list of such"):
        ms.calibrate(V, F, ATOMS, top, down, train_forces=["x"], **KW)
    with pytest.raises(ms.InvalidInput, match=r"forces\[0\] is zero: with train_forces it gives the direction"):
        ms.calibrate(V, F, ATOMS, top, np.zeros((1, 3)), train_forces=[0.1], **KW)
    # with precomputed FEM displacements, the disk-mean read-out needs the FEM's disk means, and only it reads them
    with pytest.raises(ms.InvalidInput, match="'disk-mean' with fem_displacements needs fem_disk_means"):
        ms.calibrate(V, F, ATOMS, top, down, site_readout="disk-mean", fem_displacements=[np.zeros_like(V)], **KW)
    with pytest.raises(ms.InvalidInput, match="fem_disk_means is read only with site_readout 'disk-mean'"):
        ms.calibrate(V, F, ATOMS, top, down, fem_displacements=[np.zeros_like(V)], fem_disk_means=np.zeros((1, 3)),
                     **KW)
    with pytest.raises(ms.InvalidInput, match="fem_disk_means goes with fem_displacements"):
        ms.calibrate(V, F, ATOMS, top, down, site_readout="disk-mean", fem_disk_means=np.zeros((1, 3)), **KW)
    with pytest.raises(ms.InvalidInput, match="fem_disk_means"):  # one row per training load
        ms.calibrate(V, F, ATOMS, top, down, site_readout="disk-mean", fem_displacements=[np.zeros_like(V)],
                     fem_disk_means=np.zeros((2, 3)), **KW)
    if EXE.is_file():  # the CLI prints the same words for the same values
        for option, value, words in (("--site-readout", "centre", cases[0][1]),
                                     ("--train-force", "0.2,-1", cases[2][1]),
                                     ("--site-weight", "-1", cases[6][1])):
            r = subprocess.run([str(EXE), "calibrate", "--organ", "phantom", "--kind", "volumetric", option, value],
                               capture_output=True, text=True)
            assert r.returncode != 0
            assert f"calibrate: {option} {words}" in r.stderr, r.stderr


def test_train_forces_rescale_the_rows_and_the_disk_mean_fit_reads_the_fems_disk_mean(tmp_path, monkeypatch):
    monkeypatch.setenv("MEDSPRING_FEM_CACHE", str(tmp_path))
    V, F = sphere()
    top = V[np.argmax(V[:, 2])]
    mags = [0.01, 0.02]
    # the FEM reference of both training loads, with its disk mean: the mean displacement over the disk lies
    # between the loaded node's and a fraction of it (the disk is 4 mm wide on a 10 mm sphere)
    refs = [ms.fem_reference(V, F, top, (0, 0, -f), level=1, **KW) for f in mags]
    i = int(np.argmax(V[:, 2]))
    for r in refs:
        d, u = r["disk_mean"], r["displacement"][i]
        assert d.shape == (3,) and d[2] < 0
        assert 0.5 * abs(u[2]) < abs(d[2]) <= 1.02 * abs(u[2])
    # train_forces: the one row's direction at each magnitude == the rows written out (bit for bit), and the
    # FEM solved inside == the same FEM given as fem_displacements + fem_disk_means
    fit = ms.calibrate(V, F, ATOMS, top[None, :], np.array([[0.0, 0.0, -5.0]]), train_forces=mags,
                       site_readout="disk-mean", **KW)
    assert fit["site_readout"] == "disk-mean" and fit["training_loads"] == 2
    rows = np.array([[0.0, 0.0, -f] for f in mags])
    given = dict(fem_displacements=[r["displacement"] for r in refs],
                 fem_disk_means=np.array([r["disk_mean"] for r in refs]))
    written = ms.calibrate(V, F, ATOMS, np.array([top, top]), rows, site_readout="disk-mean", **given, **KW)
    for k in ("k_surf", "k_spoke", "k_cl", "k_r"):
        assert written[k] == fit[k], k
    # the site term reads the disk mean: a FEM disk mean 1.5x larger (a softer site) gives a softer fit at the
    # site; the node read-out does not read it at all (refused above) and fits what it fitted before
    soft = dict(given, fem_disk_means=1.5 * given["fem_disk_means"])
    fit_soft = ms.calibrate(V, F, ATOMS, np.array([top, top]), rows, site_readout="disk-mean", **soft, **KW)

    def site_displacement(p):
        s = ms.HybridSettings()
        s.k_surf, s.k_spoke, s.k_cl = p["k_surf"], p["k_spoke"], p["k_cl"]
        s.surface_node.return_k = s.atom_node.return_k = p["k_r"]
        s.fixed = list(p["support"])
        body = ms.HybridKidney(ms.SurfaceMesh(V, F), ATOMS, s)
        return abs(ms.spring_displacement(body, top, (0, 0, -mags[1]), radius=KW["radius"])[i, 2])

    assert site_displacement(fit_soft) > 1.05 * site_displacement(fit)
    node = ms.calibrate(V, F, ATOMS, np.array([top, top]), rows, fem_displacements=given["fem_displacements"], **KW)
    assert node["site_readout"] == "node"
    assert any(node[k] != fit[k] for k in ("k_surf", "k_spoke", "k_cl", "k_r"))


def test_the_dask_calibration_passes_the_read_out_and_the_solved_disk_means(tmp_path, monkeypatch):
    """medspring.study.fem.calibrate (here in this process, workers=0) gives medspring.calibrate's disk-mean fit
    bit for bit: its solves return the FEM disk mean and it hands them over as fem_disk_means."""
    from medspring.study import fem

    monkeypatch.setenv("MEDSPRING_FEM_CACHE", str(tmp_path))
    V, F = sphere()
    top = V[np.argmax(V[:, 2])]
    centres, rows = np.array([top, top]), np.array([[0.0, 0.0, -0.01], [0.0, 0.0, -0.02]])
    serial = ms.calibrate(V, F, ATOMS, centres, rows, site_readout="disk-mean", **KW)
    kw = {k: v for k, v in KW.items()}
    dist = fem.calibrate(V, F, ATOMS, centres, rows, workers=0, site_readout="disk-mean", **kw)
    assert dist["parameters"]["site_readout"] == "disk-mean"
    for k in ("k_surf", "k_spoke", "k_cl", "k_r"):
        assert dist["parameters"][k] == serial[k], k
    refs = fem.references(V, F, [{"centre": top, "force": rows[1]}], workers=0, **KW)
    assert refs[0]["disk_mean"].shape == (3,) and refs[0]["disk_mean"][2] < 0


def test_the_dask_calibration_takes_train_forces_and_the_site_weight(tmp_path, monkeypatch):
    """medspring.study.fem.calibrate(train_forces=, site_weight=) (in this process, workers=0) solves the loads
    medspring.training_loads lists (each centre at each force, centre-major) and gives medspring.calibrate's
    fit with the same arguments bit for bit; a bad list is refused with the CLI's words before any solve; the
    weight reaches the fit (w = 16 fits other stiffnesses than w = 1)."""
    from medspring.study import fem

    monkeypatch.setenv("MEDSPRING_FEM_CACHE", str(tmp_path))
    V, F = sphere()
    top = V[np.argmax(V[:, 2])]
    C, rows = top[None, :], np.array([[0.0, 0.0, -5.0]])
    mags = [0.01, 0.02]
    Ce, Fe = ms.training_loads(C, rows, mags)
    assert np.array_equal(Ce, np.array([top, top])) and np.array_equal(Fe, [[0, 0, -0.01], [0, 0, -0.02]])
    assert np.array_equal(ms.training_loads(C, rows)[1], rows)  # without train_forces: the rows as given
    with pytest.raises(ms.InvalidInput) as e:
        fem.calibrate(V, F, ATOMS, C, rows, workers=0, train_forces=[0.2, -1.0], **KW)
    assert str(e.value) == "calibrate: train_forces must be > 0 N or a list of such (got '-1')"
    assert not any(tmp_path.iterdir()), "a refused call solved something"
    for w in (1.0, 16.0):
        serial = ms.calibrate(V, F, ATOMS, C, rows, train_forces=mags, site_readout="disk-mean", site_weight=w, **KW)
        dist = fem.calibrate(V, F, ATOMS, C, rows, workers=0, train_forces=mags, site_readout="disk-mean",
                             site_weight=w, **KW)
        assert dist["parameters"]["training_loads"] == 2 and dist["parameters"]["site_weight"] == w
        for k in ("k_surf", "k_spoke", "k_cl", "k_r"):
            assert dist["parameters"][k] == serial[k], (w, k)
        if w == 1.0:
            plain = serial
    assert any(serial[k] != plain[k] for k in ("k_surf", "k_spoke", "k_cl", "k_r"))
