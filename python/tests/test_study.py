"""Parameter studies on Dask distributed (medspring.study, docs/studies.md): study files, a real cluster
of dask-scheduler + dask-worker processes on 127.0.0.1 with a worker killed mid-study, --resume after the
client is killed, bit-identity with the 1-process run, and bad input refused in one line with nothing
written."""

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import medspring as ms
from conftest import REPO, bits

pytestmark = pytest.mark.skipif(not ms._medspring.has_scene, reason="built without the scene layer")

study = pytest.importorskip("medspring.study")
zarr = pytest.importorskip("zarr")
pytest.importorskip("distributed")

KIDNEY = str(REPO / "scenes" / "phantom" / "kidney_1.0N_nonlinear.json")
PYTHONPATH = str(Path(ms.__file__).resolve().parents[1])
ENV = dict(os.environ, PYTHONPATH=PYTHONPATH + os.pathsep + os.environ.get("PYTHONPATH", ""))
# Cluster workers stretch each task by 0.25 s, so that kills land mid-study however fast the machine.
WORKER_ENV = dict(ENV, MEDSPRING_STUDY_TASK_DELAY="0.25")


def small_study(runs_per_point=6, duration=150.0, batch=2):
    """3 force levels x `runs_per_point` random surface nodes on the kidney phantom."""
    return {
        "name": "test_small",
        "scene": KIDNEY,
        "set": {"duration": duration, "loads[0].direction": "inward_normal", "record.atoms": []},
        "vary": [
            {"path": "loads[0].magnitude", "values": [0.2, 0.6, 1.0]},
            {"path": "loads[0].node", "surface_node": "random"},
            {"path": "model.parameters.duffing.eta", "uniform": [0.5, 2.0]},
        ],
        "samples": {"count": runs_per_point, "method": "latin_hypercube"},
        "seed": 5,
        "outputs": {"metrics": ["contact_peak_mm", "contact_hold_mm", "max_disp_peak_mm"], "fields": {"times": [duration]}},
        "batch": batch,
    }


def write_study(tmp_path, doc, name="study.json"):
    p = tmp_path / name
    p.write_text(json.dumps(doc))
    return p


def cli(*args, timeout=120):
    return subprocess.run(
        [sys.executable, "-m", "medspring.study", *map(str, args)],
        env=ENV,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def results(out):
    g = zarr.open_group(str(Path(out) / "results.zarr"), mode="r")
    return {k: g[k][:] for k in ("run", "done", "writes", "failed", "contact_hold_mm", "load_node", "displacement")}


def assert_same(a, b):
    for k in ("run", "done", "failed", "load_node"):
        np.testing.assert_array_equal(a[k], b[k])
    np.testing.assert_array_equal(bits(a["contact_hold_mm"]), bits(b["contact_hold_mm"]))
    np.testing.assert_array_equal(bits(a["displacement"]), bits(b["displacement"]))


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The small study run in this process, without Dask (the 1-process reference)."""
    out = tmp_path_factory.mktemp("ref") / "out"
    df = study.run(small_study(), out=out, workers=0, progress=False)
    return out, df


def test_study_expands_deterministically():
    st = study.load_study(small_study())
    assert st.num_runs == 18 and st.num_batches == 9
    p = [st.params(i) for i in range(st.num_runs)]
    assert p == [study.load_study(small_study()).params(i) for i in range(st.num_runs)]
    mags = [dict(x)["loads[0].magnitude"] for x in p]
    assert mags == [0.2] * 6 + [0.6] * 6 + [1.0] * 6
    # Latin hypercube: within each grid point every sixth of [0.5, 2) holds exactly one eta.
    for g in range(3):
        eta = np.array([dict(x)["model.parameters.duffing.eta"] for x in p[6 * g : 6 * g + 6]])
        strata = np.floor((eta - 0.5) / 1.5 * 6).astype(int)
        assert sorted(strata) == list(range(6))
    nodes = [dict(x)["loads[0].node"] for x in p]
    assert all(0 <= n < 458 for n in nodes) and len(set(nodes)) > 6


def test_surface_point_samples_lie_on_the_surface_and_load_the_nearest_node():
    doc = small_study(runs_per_point=4, duration=20.0)
    doc["vary"][1] = {"path": "loads[0].point", "surface_point": "random"}
    st = study.load_study(doc)
    V, F = st.surface.V, st.surface.F
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]

    def area(x, y, z):
        return 0.5 * np.linalg.norm(np.cross(y - x, z - x), axis=-1)

    for i in range(st.num_runs):
        p = np.asarray(dict(st.params(i))["loads[0].point"])
        # inside some triangle: its three sub-triangles add up to the triangle's area
        excess = area(p, b, c) + area(a, p, c) + area(a, b, p) - area(a, b, c)
        assert excess.min() < 1e-9 * area(a, b, c).max(), f"run {i}: {p} is not on the surface"
    out = ms.run_scene(st.run_document(0))
    p = np.asarray(dict(st.params(0))["loads[0].point"])
    assert out["load_node"] == int(np.argmin(np.linalg.norm(V - p, axis=1)))


def test_reference_run_is_complete_and_physical(reference):
    out, df = reference
    r = results(out)
    assert r["done"].all() and (r["writes"] == 1).all() and not r["failed"].any()
    assert len(df) == 18 and list(df["run"]) == list(range(18))
    # Under the same force the held displacement grows with the force (per node sample it varies).
    med = [np.median(df[df["loads_0_magnitude"] == m]["contact_hold_mm"]) for m in (0.2, 0.6, 1.0)]
    assert med[0] < med[1] < med[2]
    # The stored field at the load node is the contact displacement of the summary.
    for i in range(18):
        u = np.linalg.norm(r["displacement"][i, 0, r["load_node"][i]])
        assert u == pytest.approx(df["contact_hold_mm"][i], rel=1e-12, abs=1e-15)
    assert (out / "summary.csv").is_file() and (out / "study.md").is_file()
    report = (out / "study.md").read_text()
    assert "## Sensitivity" in report and "plots/contact_hold_mm.png" in report
    assert (out / "plots" / "contact_hold_mm.png").stat().st_size > 1000
    xr = pytest.importorskip("xarray")
    ds = xr.open_zarr(str(out / "results.zarr"), consolidated=False, mask_and_scale=False)
    assert ds["displacement"].dims == ("run", "time", "node", "xyz")
    assert ds["rest_positions"].shape == (458, 3)
    np.testing.assert_array_equal(ds["load_node"].values, r["load_node"])  # integers stay integers


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Cluster:
    """A dask-scheduler and `n` single-threaded dask-worker processes on 127.0.0.1."""

    def __init__(self, tmp, n):
        self.port = free_port()
        self.address = f"tcp://127.0.0.1:{self.port}"
        self.procs = []
        log = open(tmp / "scheduler.log", "w")
        self.scheduler = subprocess.Popen(
            ["dask-scheduler", "--host", "127.0.0.1", "--port", str(self.port), "--dashboard-address", ":0", "--no-show"],
            env=ENV, stdout=log, stderr=log,
        )
        self.procs.append(self.scheduler)
        self.workers = []
        for k in range(n):
            wlog = open(tmp / f"worker{k}.log", "w")
            w = subprocess.Popen(
                ["dask-worker", self.address, "--nthreads", "1", "--nworkers", "1", "--no-nanny",
                 "--host", "127.0.0.1", "--no-dashboard", "--local-directory", str(tmp / f"w{k}")],
                env=WORKER_ENV, stdout=wlog, stderr=wlog,
            )
            self.workers.append(w)
            self.procs.append(w)
        from distributed import Client

        deadline = time.time() + 60
        while True:
            try:
                with Client(self.address, timeout=5) as c:
                    c.wait_for_workers(n, timeout=max(1, deadline - time.time()))
                break
            except Exception:
                if time.time() > deadline:
                    raise
                time.sleep(0.5)

    def close(self):
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
        for p in self.procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()


def done_count(out):
    path = Path(out) / "results.zarr" / "done"
    if not (path / ".zarray").is_file():
        return 0
    try:
        return int(zarr.open_array(str(path), mode="r")[:].sum())
    except Exception:  # a chunk being replaced right now
        return 0


@pytest.mark.slow
def test_cluster_survives_a_killed_worker(tmp_path, reference):
    ref_out, _ = reference
    cluster = Cluster(tmp_path, 3)
    try:
        spec = write_study(tmp_path, small_study())
        out = tmp_path / "out"
        client = subprocess.Popen(
            [sys.executable, "-m", "medspring.study", str(spec), "--out", str(out), "--scheduler", cluster.address, "--quiet"],
            env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )
        deadline = time.time() + 60
        while done_count(out) < 2 and client.poll() is None and time.time() < deadline:
            time.sleep(0.02)
        victim = cluster.workers[0]
        victim.send_signal(signal.SIGKILL)  # mid-study: its running and finished-but-unfetched tasks are lost
        killed_at = done_count(out)
        stdout, stderr = client.communicate(timeout=120)
        assert client.returncode == 0, stderr
        assert victim.wait(timeout=10) == -signal.SIGKILL
        assert killed_at < 18, "the study finished before the worker was killed; nothing was tested"
        r = results(out)
        assert r["done"].all(), "lost runs"
        assert (r["writes"] == 1).all(), "duplicated runs"
        assert_same(r, results(ref_out))
    finally:
        cluster.close()


@pytest.mark.slow
def test_resume_after_the_client_is_killed(tmp_path, reference):
    ref_out, _ = reference
    cluster = Cluster(tmp_path, 2)
    try:
        spec = write_study(tmp_path, small_study())
        out = tmp_path / "out"
        client = subprocess.Popen(
            [sys.executable, "-m", "medspring.study", str(spec), "--out", str(out), "--scheduler", cluster.address, "--quiet"],
            env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        )
        deadline = time.time() + 60
        while done_count(out) < 4 and client.poll() is None and time.time() < deadline:
            time.sleep(0.01)
        client.send_signal(signal.SIGKILL)
        client.communicate(timeout=30)
        partial = done_count(out)
        assert 0 < partial < 18, f"{partial} runs done when the client was killed; nothing was tested"
        again = cli(spec, "--out", out, "--scheduler", cluster.address)
        assert again.returncode != 0 and "--resume" in again.stderr  # not without --resume
        before = results(out)
        resumed = cli(spec, "--out", out, "--scheduler", cluster.address, "--resume", "--quiet")
        assert resumed.returncode == 0, resumed.stderr
        r = results(out)
        assert r["done"].all() and (r["writes"] == 1).all(), "lost or duplicated runs"
        # The runs finished before the kill were not redone.
        np.testing.assert_array_equal(r["writes"][before["done"] == 1], 1)
        assert_same(r, results(ref_out))
    finally:
        cluster.close()


def test_local_cluster_matches_the_1_process_run(tmp_path, reference):
    ref_out, _ = reference
    out = tmp_path / "out"
    df = study.run(small_study(), out=out, workers=2, progress=False, report=False)
    assert len(df) == 18
    assert_same(results(out), results(ref_out))


def one_line_error(res):
    assert res.returncode == 2, res.stdout + res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    return lines[0]


def test_declared_study_settings_are_read_checked_and_overridden_by_their_declaration(tmp_path):
    # samples, seed, batch, max_runs: declared in scene/study_settings.hpp (docs/parameters.md)
    st = study.load_study(small_study())
    assert (st.settings.seed, st.settings.batch, st.settings.samples.count) == (5, 2, 6)
    assert st.method == "latin_hypercube" and st.settings.max_runs == ms._medspring.StudySettings().max_runs
    over = study.load_study(small_study(), settings="seed=7,samples.count=3,samples.method=random")
    assert (over.seed, over.count, over.method, over.num_runs) == (7, 3, "random", 9)
    assert study.load_study(small_study(), settings={"batch": 5}).num_batches == 4
    with pytest.raises(ms.InvalidInput, match=r"study: --set batch: must be an integer in 1\.\.100000 \(got 0\)"):
        study.load_study(small_study(), settings={"batch": 0})
    bad = small_study()
    bad["batch"] = 0
    with pytest.raises(ms.InvalidInput, match=r"^study: batch: must be an integer in 1\.\.100000 \(got 0\)$"):
        study.load_study(bad)
    bad = small_study()
    bad["samples"]["method"] = "sobol"
    with pytest.raises(ms.InvalidInput, match="samples.method: expected 'random' or 'latin_hypercube'"):
        study.load_study(bad)
    # the command line: --set reaches the same declaration
    msg = one_line_error(cli(write_study(tmp_path, small_study()), "--out", tmp_path / "o", "--workers", "0",
                             "--set", "seed=-1"))
    assert "--set seed: must be >= 0 (got -1)" in msg
    assert not (tmp_path / "o").exists()


def test_bad_studies_are_refused_naming_the_json_path(tmp_path):
    bad = small_study()
    bad["vary"][0]["path"] = "model.parameters.k_srf"
    msg = one_line_error(cli(write_study(tmp_path, bad), "--out", tmp_path / "o1", "--workers", "0"))
    assert "vary[0].path" in msg and "k_srf" in msg
    bad = small_study()
    bad["vary"][0] = {"path": "loads[0].magnitude", "values": []}
    msg = one_line_error(cli(write_study(tmp_path, bad), "--out", tmp_path / "o2", "--workers", "0"))
    assert "vary[0].values" in msg and "empty" in msg
    bad = small_study()
    bad["vary"][0] = {"path": "loads[0].magnitude", "grid": {"from": 0, "to": 1, "num": 0}}
    msg = one_line_error(cli(write_study(tmp_path, bad), "--out", tmp_path / "o3", "--workers", "0"))
    assert "vary[0].grid.num" in msg
    bad = small_study()
    bad["vary"] = [
        {"path": "loads[0].magnitude", "grid": {"from": 0, "to": 1, "num": 1000}},
        {"path": "model.parameters.k_surf", "grid": {"from": 0.01, "to": 0.1, "num": 1000}},
        {"path": "model.parameters.duffing.eta", "grid": {"from": 0.5, "to": 2, "num": 1000}},
    ]
    bad.pop("samples")
    msg = one_line_error(cli(write_study(tmp_path, bad), "--out", tmp_path / "o4", "--workers", "0"))
    assert "1000000000 runs" in msg and "--yes" in msg
    bad = small_study()
    bad["outputs"]["metrics"] = ["contact_hold"]
    msg = one_line_error(cli(write_study(tmp_path, bad), "--out", tmp_path / "o5", "--workers", "0"))
    assert "outputs.metrics[0]" in msg
    bad = small_study()
    bad["vary"][1]["surface_node"] = "all"
    msg = one_line_error(cli(write_study(tmp_path, bad), "--out", tmp_path / "o6", "--workers", "0"))
    assert "vary[1].surface_node" in msg
    for k in range(1, 7):
        assert not (tmp_path / f"o{k}").exists(), "a refused study wrote its folder"


def test_unreachable_scheduler_fails_fast(tmp_path):
    spec = write_study(tmp_path, small_study())
    address = f"tcp://127.0.0.1:{free_port()}"
    t0 = time.time()
    with pytest.raises(ms.InvalidInput, match="cannot reach the scheduler"):
        study.connect(address)
    assert time.time() - t0 < 10  # the connection attempt gives up after 6 s
    t0 = time.time()
    msg = one_line_error(cli(spec, "--out", tmp_path / "o", "--scheduler", address))
    assert time.time() - t0 < 30  # the same through the command (+ start-up and validation on a loaded machine)
    assert "cannot reach the scheduler" in msg and address in msg
    assert not (tmp_path / "o").exists()


def test_folder_of_another_study_is_refused(tmp_path, reference):
    ref_out, _ = reference
    other = small_study()
    other["seed"] = 6
    spec = write_study(tmp_path, other)
    listing = sorted(p.name for p in ref_out.iterdir())
    stamp = (ref_out / "results.zarr" / "done" / "0").stat().st_mtime_ns
    msg = one_line_error(cli(spec, "--out", ref_out, "--workers", "0", "--resume"))
    assert "another study" in msg
    assert sorted(p.name for p in ref_out.iterdir()) == listing
    assert (ref_out / "results.zarr" / "done" / "0").stat().st_mtime_ns == stamp
    (tmp_path / "junk").mkdir()
    (tmp_path / "junk" / "x.txt").write_text("x")
    msg = one_line_error(cli(spec, "--out", tmp_path / "junk", "--workers", "0"))
    assert "holds no study" in msg


def test_medspring_study_command_runs_from_the_build_tree(tmp_path):
    exe = Path(PYTHONPATH).parent / "apps" / "medspring"
    if not exe.is_file():
        pytest.skip(f"{exe} is not built")
    spec = write_study(tmp_path, small_study(runs_per_point=1, duration=20.0, batch=3))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # the command sets it itself
    r = subprocess.run([str(exe), "study", str(spec), "--out", str(tmp_path / "o"), "--workers", "0", "--quiet"],
                       env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    import pandas as pd

    df = pd.read_csv(tmp_path / "o" / "summary.csv")
    assert list(df["run"]) == [0, 1, 2] and not df["failed"].any()
    again = subprocess.run([str(exe), "study", str(spec), "--out", str(tmp_path / "o"), "--workers", "0"],
                           env=env, capture_output=True, text=True, timeout=120)
    assert again.returncode == 2 and len(again.stderr.strip().splitlines()) == 1 and "--resume" in again.stderr
