"""The study folder: DIR/study.json (what was asked, with its fingerprint), DIR/results.zarr (every run,
chunked one batch per chunk, written as batches complete) and DIR/summary.csv (pandas, rewritten from
the store). The Zarr arrays carry xarray's `_ARRAY_DIMENSIONS`, so
`xarray.open_zarr(DIR/results.zarr, consolidated=False, mask_and_scale=False)` loads them as one
Dataset over (run, time, node, xyz).

A batch's arrays are written first and its `done` flags last; every chunk write is a file written under
a temporary name and renamed (zarr's DirectoryStore), so a killed client leaves whole batches or none:
--resume redoes exactly the batches whose flags are not all set.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np

from .._medspring import InvalidInput, study_settings_json
from .spec import Study

STUDY_FILE = "study.json"
STORE = "results.zarr"
ERROR_LEN = 240
TEXT_LEN = 128  # a varied value that is not a number or a 3-vector, as JSON text


def _dims(arr, dims):
    arr.attrs["_ARRAY_DIMENSIONS"] = list(dims)
    return arr


def check_folder(out: Path, st: Study, resume: bool) -> bool:
    """Whether `out` already holds this study (to be resumed). Raises InvalidInput, writing nothing,
    when it holds something else or this study without resume."""
    if not out.exists():
        return False
    if not out.is_dir():
        raise InvalidInput(f"{out}: exists and is not a folder")
    entries = [p.name for p in out.iterdir()]
    if not entries:
        return False
    meta = out / STUDY_FILE
    if not meta.is_file():
        raise InvalidInput(f"{out}: not empty and holds no study ({STUDY_FILE} missing): choose another --out")
    try:
        old = json.loads(meta.read_text())
        fp, name = old["fingerprint"], old.get("name", "?")
    except (OSError, ValueError, KeyError, TypeError):
        raise InvalidInput(f"{out}/{STUDY_FILE}: unreadable: choose another --out") from None
    if fp != st.fingerprint():
        raise InvalidInput(
            f"{out}: holds the results of another study ('{name}', fingerprint {fp}; this one is "
            f"'{st.name}', {st.fingerprint()}): choose another --out"
        )
    if not resume:
        raise InvalidInput(f"{out}: already holds this study's results: pass --resume to complete them")
    if not (out / STORE).is_dir():
        raise InvalidInput(f"{out}: {STORE} is missing: choose another --out")
    return True


class Store:
    """The results of one study on disk."""

    def __init__(self, out: Path, st: Study, create: bool):
        import zarr

        self.out, self.st = out, st
        path = str(out / STORE)
        if create:
            out.mkdir(parents=True, exist_ok=True)
            self.g = zarr.open_group(path, mode="w")
            self._create()
            meta = {
                "name": st.name,
                "fingerprint": st.fingerprint(),
                "origin": st.origin,
                "num_runs": st.num_runs,
                "batch": st.batch,
                "settings": json.loads(study_settings_json(st.settings)),  # the declared keys (docs/parameters.md)
                "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            }
            tmp = out / (STUDY_FILE + ".tmp")
            tmp.write_text(json.dumps(meta, indent=2) + "\n")
            os.replace(tmp, out / STUDY_FILE)
        else:
            self.g = zarr.open_group(path, mode="r+")

    def _create(self):
        st, g = self.st, self.g
        N, B = st.num_runs, st.batch
        from ..scenes import scene_runner

        model = scene_runner().model(json.dumps(st.scene), "/", "scene")
        S = st.num_surface_nodes
        g.attrs.update(
            {
                "name": st.name,
                "description": st.description,
                "fingerprint": st.fingerprint(),
                "scene": json.dumps(st.scene),
                "varied": [{"path": v.path, "name": v.name, "kind": v.kind} for v in st.vary],
                "metrics": st.metrics,
                "units": "mm, g, ms, N",
            }
        )
        _dims(g.full("run", shape=(N,), chunks=(B,), dtype=np.int64, fill_value=-1), ["run"])
        _dims(g.zeros("seed", shape=(N,), chunks=(B,), dtype=np.uint32), ["run"])
        for v in st.vary:
            name, lay = f"param_{v.name}", v.layout
            if lay == "vec3":
                a = g.full(name, shape=(N, 3), chunks=(B, 3), dtype=np.float64, fill_value=np.nan)
                _dims(a, ["run", "xyz"])
            elif lay == "text":
                a = _dims(g.full(name, shape=(N,), chunks=(B,), dtype=f"<U{TEXT_LEN}", fill_value=""), ["run"])
            elif lay == "int":
                a = _dims(g.full(name, shape=(N,), chunks=(B,), dtype=np.int64, fill_value=-1), ["run"])
            else:
                a = _dims(g.full(name, shape=(N,), chunks=(B,), dtype=np.float64, fill_value=np.nan), ["run"])
            a.attrs["path"] = v.path
        for m in st.metrics:
            _dims(g.full(m, shape=(N,), chunks=(B,), dtype=np.float64, fill_value=np.nan), ["run"])
        _dims(g.full("load_node", shape=(N,), chunks=(B,), dtype=np.int64, fill_value=-1), ["run"])
        _dims(g.full("load_force", shape=(N, 3), chunks=(B, 3), dtype=np.float64, fill_value=np.nan), ["run", "xyz"])
        _dims(g.zeros("engine_seconds", shape=(N,), chunks=(B,), dtype=np.float64), ["run"])
        _dims(g.zeros("failed", shape=(N,), chunks=(B,), dtype=np.uint8), ["run"])
        _dims(g.full("error", shape=(N,), chunks=(B,), dtype=f"<U{ERROR_LEN}", fill_value=""), ["run"])
        _dims(g.zeros("writes", shape=(N,), chunks=(B,), dtype=np.uint8), ["run"])
        _dims(g.zeros("done", shape=(N,), chunks=(B,), dtype=np.uint8), ["run"])
        nb = st.num_batches
        _dims(g.zeros("batch_seconds", shape=(nb,), chunks=(1024,), dtype=np.float64), ["batch"])
        _dims(g.create_dataset("rest_positions", data=model["rest_surface"]), ["node", "xyz"])
        _dims(g.create_dataset("rest_normals", data=model["normals"]), ["node", "xyz"])
        _dims(g.create_dataset("faces", data=np.asarray(model["faces"], dtype=np.int64)), ["face", "corner"])
        if st.field_times:
            T = len(st.field_times)
            _dims(g.create_dataset("time", data=np.asarray(st.field_times, dtype=np.float64)), ["time"])
            a = g.full(
                "displacement",
                shape=(N, T, S, 3),
                chunks=(B, T, S, 3),
                dtype=st.field_dtype,
                fill_value=np.nan,
            )
            _dims(a, ["run", "time", "node", "xyz"])
            a.attrs["units"] = "mm"
            a.attrs["description"] = (
                "surface displacement (position - rest_positions) at the first frame reaching each time"
            )

    def batch_slice(self, b: int) -> slice:
        return slice(b * self.st.batch, min(self.st.num_runs, (b + 1) * self.st.batch))

    def missing_batches(self) -> list:
        done = self.g["done"][:]
        B = self.st.batch
        out = []
        for b in range(self.st.num_batches):
            if not done[b * B : (b + 1) * B].all():
                out.append(b)
        return out

    def num_done(self) -> tuple:
        done = self.g["done"][:].astype(bool)
        failed = self.g["failed"][:].astype(bool)
        return int(done.sum()), int((done & failed).sum())

    def write(self, b: int, task_runs: list, result: dict) -> None:
        """Writes one finished batch (its flags last)."""
        g, st = self.g, self.st
        sl = self.batch_slice(b)
        n = sl.stop - sl.start
        if list(result["index"]) != list(range(sl.start, sl.stop)):
            raise RuntimeError(f"batch {b}: the result holds runs {result['index'][:3]}..., expected {sl}")
        g["run"][sl] = np.arange(sl.start, sl.stop, dtype=np.int64)
        g["seed"][sl] = np.array([st.run_seed(i) for i in range(sl.start, sl.stop)], dtype=np.uint32)
        for k, v in enumerate(st.vary):
            vals = [dict(ov)[v.path] for _, ov in task_runs]
            arr = g[f"param_{v.name}"]
            if v.layout == "text":
                vals = [json.dumps(x)[:TEXT_LEN] for x in vals]
            arr[sl] = np.asarray(vals, dtype=arr.dtype).reshape((n,) + arr.shape[1:])
        for j, m in enumerate(st.metrics):
            g[m][sl] = result["metrics"][:, j]
        g["load_node"][sl] = result["load_node"]
        g["load_force"][sl] = result["load_force"]
        g["engine_seconds"][sl] = result["engine_seconds"]
        g["failed"][sl] = result["failed"]
        g["error"][sl] = np.array([e[:ERROR_LEN] for e in result["errors"]], dtype=f"<U{ERROR_LEN}")
        if st.field_times:
            g["displacement"][sl] = result["fields"]
        g["batch_seconds"][b] = result["task_seconds"]
        g["writes"][sl] = g["writes"][sl] + 1
        g["done"][sl] = 1

    def frame(self):
        """The summary table (pandas) of the finished runs."""
        import pandas as pd

        g, st = self.g, self.st
        done = g["done"][:].astype(bool)
        cols = {"run": g["run"][:][done], "seed": g["seed"][:][done]}
        for v in st.vary:
            a = g[f"param_{v.name}"][:][done]
            if a.ndim == 2:
                for d, ax in enumerate("xyz"):
                    cols[f"{v.name}_{ax}"] = a[:, d]
            else:
                cols[v.name] = a
        cols["load_node"] = g["load_node"][:][done]
        lf = g["load_force"][:][done]
        for d, ax in enumerate("xyz"):
            cols[f"load_force_{ax}"] = lf[:, d]
        for m in st.metrics:
            cols[m] = g[m][:][done]
        cols["engine_seconds"] = g["engine_seconds"][:][done]
        cols["failed"] = g["failed"][:][done].astype(bool)
        cols["error"] = g["error"][:][done]
        return pd.DataFrame(cols)

    def write_csv(self) -> Path:
        path = self.out / "summary.csv"
        tmp = self.out / "summary.csv.tmp"
        self.frame().to_csv(tmp, index=False, float_format="%.17g")
        os.replace(tmp, path)
        return path
