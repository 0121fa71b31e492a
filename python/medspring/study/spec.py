"""Study files (docs/studies.md): a base scene plus the varied quantities and what each run reports.
Parsed and validated here; every error is a medspring.InvalidInput whose message starts with the study
file and the JSON path at fault ("kidney.json: vary[1].grid.num: must be >= 1 (got 0)").

Runs are numbered 0..N-1: run i = grid point i // count, sample i % count, where the grid is the product
of every `values`/`grid` entry (in file order) and count is samples.count (1 without sampled entries).
Every sampled value of run i is drawn from numpy's PCG64 seeded with SeedSequence([seed, i]) (random),
or from a stratified permutation seeded by [seed, grid point, dimension] (latin_hypercube), so a run's
parameters depend only on the study and i: reruns and resumed runs are bit-identical.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import _medspring
from .._medspring import InvalidInput, IoError, StudySettings, study_settings_from_json
from ..scenes import apply_overrides, parse_path, scene_document, without_key_times

# The lists and objects of a study file and the metrics are declared once, in C++
# (scene/study_schema.hpp): check_keys walks a study file against that declaration; docs/parameters.md
# ("Study file", "Study metrics") is generated from it. samples, seed, batch and max_runs are declared in
# scene/study_settings.hpp (StudySettings): their checks, defaults, docs and `medspring study --set`.
_SCHEMA = _medspring.study_file_schema()
SCHEMA_KEYS = {k["path"]: k for k in _SCHEMA["keys"]}
METRICS = tuple(m["name"] for m in _SCHEMA["metrics"] if m["by_default"])
# Metrics of the first tool of a scene with "tools" (docs/tools.md); asked for by name, not by default.
TOOL_METRICS = tuple(m["name"] for m in _SCHEMA["metrics"] if not m["by_default"])
SETTINGS_KEYS = tuple(spec["key"] for spec in StudySettings._params)


def _declared_children(path: str) -> list:
    """The declared keys of the object at schema path `path` ("" the file, "vary[]", "vary[].grid")."""
    prefix = path + "." if path else ""
    return [p[len(prefix):] for p in SCHEMA_KEYS
            if p.startswith(prefix) and p != path and not any(c in p[len(prefix):] for c in ".[")]


STUDY_KEYS = tuple(_declared_children("")) + SETTINGS_KEYS
LISTED_KINDS = ("values", "grid")
SAMPLED_KINDS = tuple(k for k in _declared_children("vary[]") if SCHEMA_KEYS["vary[]." + k]["one_of"]
                      and k not in LISTED_KINDS)
DEFAULT_MAX_RUNS = StudySettings().max_runs


class _Where:
    def __init__(self, origin: str):
        self.origin = origin

    def fail(self, path: str, message: str):
        raise InvalidInput(f"{self.origin}: {path}: {message}")


def _number(w: _Where, v: Any, path: str, integer: bool = False) -> float:
    ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
    if integer:
        ok = ok and float(v).is_integer()
    if not ok:
        w.fail(path, f"expected a finite {'integer' if integer else 'number'}; got {json.dumps(v)}")
    return int(v) if integer else float(v)


def _below(bound: dict, v: float) -> bool:
    return v <= bound["lo"] if bound["lo_open"] else v < bound["lo"]


def check_keys(w: "_Where", value: Any, path: str = "", at: str = "", extra: tuple = ()) -> None:
    """Checks `value` against the declared key `path` of a study file (scene/study_schema.hpp; "" the
    file itself, whose keys `extra` are checked elsewhere): type, lower bound, allowed words, unknown and
    missing keys, exactly one of a group, then every declared child. Errors name the JSON path `at`."""
    k = SCHEMA_KEYS.get(path, {"type": "object", "open": False, "non_empty": False})
    t = k["type"]
    if t == "object":
        if not isinstance(value, dict):
            w.fail(at or "study", f"expected an object; got {json.dumps(value)[:60]}")
        if k["open"]:
            return
        names = _declared_children(path)
        for key in value:
            if key not in names and key not in extra:
                w.fail(f"{at}.{key}" if at else key, f"unknown key (expected one of {', '.join(names + list(extra))})")
        for n in names:
            if SCHEMA_KEYS[_join(path, n)]["required"] and n not in value:
                w.fail(at or "study", f"missing key '{n}'")
        for group in dict.fromkeys(SCHEMA_KEYS[_join(path, n)]["one_of"] for n in names):
            members = [n for n in names if group and SCHEMA_KEYS[_join(path, n)]["one_of"] == group]
            if members and sum(n in value for n in members) != 1:
                w.fail(at, f"give exactly one of {', '.join(members)} (got {sum(n in value for n in members)})")
        for key, v in value.items():
            if key in names:
                check_keys(w, v, _join(path, key), f"{at}.{key}" if at else key)
    elif t == "list":
        if not isinstance(value, list):
            w.fail(at, f"expected a list; got {json.dumps(value)[:60]}")
        if k["non_empty"] and not value:
            w.fail(at, "is empty: at least one element is needed")
        if path + "[]" in SCHEMA_KEYS:
            for i, e in enumerate(value):
                check_keys(w, e, path + "[]", f"{at}[{i}]")
    elif t in ("number", "integer"):
        v = _number(w, value, at, integer=t == "integer")
        if _below(k, v):
            w.fail(at, f"must be {k['range']} (got {v})")
    elif t in ("range", "integer range"):
        if not (isinstance(value, list) and len(value) == 2):
            w.fail(at, f"expected [low, high]; got {json.dumps(value)[:60]}")
        low, high = (_number(w, x, f"{at}[{i}]", integer=t == "integer range") for i, x in enumerate(value))
        for i, x in enumerate((low, high)):
            if _below(k, x):
                w.fail(f"{at}[{i}]", f"must be {k['range']} (got {x})")
        if not high > low:
            w.fail(at, f"needs low < high (got {low}, {high})")
    elif t == "bool":
        if not isinstance(value, bool):
            w.fail(at, f"expected true or false; got {json.dumps(value)[:60]}")
    elif t == "text":
        if not isinstance(value, str) or not value:
            w.fail(at, f"expected non-empty text; got {json.dumps(value)[:60]}")
    elif t == "word":
        if not isinstance(value, str) or value not in k["words"]:
            choices = " or ".join(json.dumps(x) for x in k["words"]) if len(k["words"]) <= 3 else (
                "one of " + ", ".join(k["words"]))
            w.fail(at, f"expected {choices}; got {json.dumps(value)[:60]}")
    elif t == "text or object":
        if not isinstance(value, (str, dict)):
            w.fail(at, f"expected a file name or an object; got {json.dumps(value)[:60]}")


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


@dataclass
class Vary:
    """One varied quantity."""

    path: str  # scene parameter path, e.g. "loads[0].magnitude"
    kind: str  # LISTED_KINDS or SAMPLED_KINDS
    where: str  # "vary[k]"
    values: list = field(default_factory=list)  # listed kinds: every value; choice: the options
    low: float = 0.0
    high: float = 0.0

    @property
    def name(self) -> str:
        """Column / array name: the path with brackets and dots as underscores."""
        return "".join(c if c.isalnum() else "_" for c in self.path).strip("_").replace("__", "_")

    @property
    def sampled(self) -> bool:
        return self.kind in SAMPLED_KINDS

    @property
    def layout(self) -> str:
        """How the values are stored: "int", "float", "vec3" (3 numbers) or "text" (JSON of anything
        else: names, mixed lists)."""
        if self.kind in ("integers", "surface_node"):
            return "int"
        if self.kind in ("uniform", "log_uniform"):
            return "float"
        if self.kind in ("unit_vector", "surface_point"):
            return "vec3"

        def number(x):
            return isinstance(x, (int, float)) and not isinstance(x, bool)

        if all(number(x) for x in self.values):
            return "int" if all(isinstance(x, int) for x in self.values) else "float"
        if all(isinstance(x, list) and len(x) == 3 and all(number(c) for c in x) for x in self.values):
            return "vec3"
        return "text"

    @property
    def width(self) -> int:
        """Values per run: 3 for vectors, else 1."""
        return 3 if self.layout == "vec3" else 1

    def from_unit(self, u: np.ndarray, surface: "Surface"):
        """The value for uniform numbers u in [0, 1) (self.dims of them)."""
        if self.kind == "uniform":
            return self.low + (self.high - self.low) * float(u[0])
        if self.kind == "log_uniform":
            return float(math.exp(math.log(self.low) + (math.log(self.high) - math.log(self.low)) * float(u[0])))
        if self.kind == "integers":
            return int(self.low + min(int(u[0] * (self.high - self.low)), int(self.high - self.low) - 1))
        if self.kind == "choice":
            return self.values[min(int(u[0] * len(self.values)), len(self.values) - 1)]
        if self.kind == "surface_node":
            return min(int(u[0] * surface.num_nodes), surface.num_nodes - 1)
        if self.kind == "surface_point":
            return surface.point(u)
        # unit_vector: uniform on the sphere
        z = 2.0 * float(u[0]) - 1.0
        phi = 2.0 * math.pi * float(u[1])
        r = math.sqrt(max(0.0, 1.0 - z * z))
        return [r * math.cos(phi), r * math.sin(phi), z]

    @property
    def dims(self) -> int:
        return {"unit_vector": 2, "surface_point": 3}.get(self.kind, 1)


class Surface:
    """The base model's rest surface, for surface_node / surface_point samples."""

    def __init__(self, V=None, F=None):
        self.V = np.zeros((0, 3)) if V is None else np.asarray(V, dtype=np.float64)
        self.F = np.zeros((0, 3), dtype=np.int64) if F is None else np.asarray(F, dtype=np.int64)
        self.num_nodes = len(self.V)
        if len(self.F):
            a, b, c = self.V[self.F[:, 0]], self.V[self.F[:, 1]], self.V[self.F[:, 2]]
            area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
            self.cumulative = np.cumsum(area) / area.sum()

    def point(self, u) -> list:
        """A point uniform over the surface area: triangle by area (u[0]), then uniform in it."""
        f = min(int(np.searchsorted(self.cumulative, float(u[0]), side="right")), len(self.F) - 1)
        r1, r2 = math.sqrt(float(u[1])), float(u[2])
        a, b, c = self.V[self.F[f]]
        return [float(x) for x in (1 - r1) * a + r1 * (1 - r2) * b + r1 * r2 * c]


@dataclass
class Study:
    """A parsed, validated study."""

    name: str
    description: str
    origin: str  # the study file (messages)
    scene: dict  # base scene document, every default filled in, paths absolute, `set` applied
    vary: list  # [Vary]
    count: int  # samples per grid point
    method: str  # random | latin_hypercube
    seed: int
    metrics: list
    field_times: list  # ms; empty: no fields
    field_dtype: str  # float64 | float32
    batch: int
    max_runs: int
    settings: StudySettings = field(default_factory=StudySettings)  # the declared keys, as read
    num_surface_nodes: int = 0  # of the base model (set by resolve_model)
    surface: Surface = field(default_factory=Surface)  # its rest surface (set by resolve_model)
    grid_shape: tuple = ()

    @property
    def num_runs(self) -> int:
        return int(np.prod(self.grid_shape, dtype=np.int64)) * self.count if self.grid_shape else self.count

    @property
    def num_batches(self) -> int:
        return -(-self.num_runs // self.batch)

    def fingerprint(self) -> str:
        """What identifies the study's results: scene, varied quantities, samples, seed, outputs, batch."""
        doc = {
            "scene": self.scene,
            "vary": [(v.path, v.kind, v.values, v.low, v.high) for v in self.vary],
            "count": self.count,
            "method": self.method,
            "seed": self.seed,
            "metrics": self.metrics,
            "field_times": self.field_times,
            "field_dtype": self.field_dtype,
            "batch": self.batch,
        }
        return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:16]

    def run_seed(self, i: int) -> int:
        return int(np.random.SeedSequence([self.seed, i]).generate_state(1)[0])

    def _unit_samples(self, g: int, s: int, i: int) -> list:
        """u in [0, 1) for every sampled dimension of run i (grid point g, sample s)."""
        sampled = [v for v in self.vary if v.sampled]
        total = sum(v.dims for v in sampled)
        rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence([self.seed, i])))
        jitter = rng.random(total)
        if self.method == "random":
            return list(jitter)
        out = []
        for d in range(total):  # latin hypercube: stratum of sample s along dimension d
            perm = np.random.Generator(np.random.PCG64(np.random.SeedSequence([self.seed, g, d, 7]))).permutation(
                self.count
            )
            out.append((perm[s] + jitter[d]) / self.count)
        return out

    def params(self, i: int) -> list:
        """[(path, value)] of run i, in the order of `vary`."""
        if not 0 <= i < self.num_runs:
            raise InvalidInput(f"run {i}: out of range [0, {self.num_runs})")
        g, s = divmod(i, self.count)
        listed = [v for v in self.vary if not v.sampled]
        idx = np.unravel_index(g, self.grid_shape) if listed else ()
        u = self._unit_samples(g, s, i) if any(v.sampled for v in self.vary) else []
        out, li, ui = [], 0, 0
        for v in self.vary:
            if v.sampled:
                out.append((v.path, v.from_unit(np.asarray(u[ui : ui + v.dims]), self.surface)))
                ui += v.dims
            else:
                out.append((v.path, v.values[int(idx[li])]))
                li += 1
        return out

    def run_document(self, i: int) -> dict:
        return apply_overrides(self.scene, self.params(i))


def _parse_vary(w: _Where, k: int, e: dict) -> Vary:
    """One entry of `vary`, already checked against its declaration (check_keys)."""
    where = f"vary[{k}]"
    kind = next(x for x in LISTED_KINDS + SAMPLED_KINDS if x in e)
    path = e["path"]
    try:
        parse_path(path)
    except InvalidInput as err:
        w.fail(f"{where}.path", str(err))
    v = Vary(path=path, kind=kind, where=where)
    spec = e[kind]
    at = f"{where}.{kind}"
    if kind in ("values", "choice"):
        v.values = list(spec)
    elif kind == "grid":
        a, b, n = float(spec["from"]), float(spec["to"]), int(spec["num"])
        if spec.get("log", False):
            if a <= 0 or b <= 0:
                w.fail(at, "a log grid needs from > 0 and to > 0")
            v.values = [float(x) for x in np.geomspace(a, b, n)]
        else:
            v.values = [float(x) for x in np.linspace(a, b, n)]
    elif kind in ("uniform", "log_uniform", "integers"):
        cast = int if kind == "integers" else float
        v.low, v.high = cast(spec[0]), cast(spec[1])
    return v


def _apply_settings(s: StudySettings, settings: Any, origin: str) -> tuple:
    """Overrides of the declared settings: a StudySettings, a dict {name: value} ("samples.count": 4) or
    "NAME=VALUE[,NAME=VALUE]" text (`medspring study --set`). Returns (settings, names set)."""
    if settings is None:
        return s, ()
    if isinstance(settings, StudySettings):
        return settings, ("samples.count",) if settings.samples.count != 1 else ()
    if isinstance(settings, str):
        items = []
        for item in settings.split(","):
            name, eq, value = item.partition("=")
            if not eq or not name:
                raise InvalidInput(f"{origin}: --set: expected NAME=VALUE (got '{item}')")
            items.append((name.strip(), value.strip()))
    elif isinstance(settings, dict):
        items = list(settings.items())
    else:
        raise InvalidInput(f"{origin}: settings: expected a StudySettings, a dict or NAME=VALUE text")
    for name, value in items:
        text = ("true" if value else "false") if isinstance(value, bool) else str(value)
        try:
            s.set_text(name, text)
        except InvalidInput as e:
            raise InvalidInput(f"{origin}: --set {e}") from None
    return s, tuple(name for name, _ in items)


def load_study(study: Any, base_dir: str | os.PathLike | None = None, settings: Any = None) -> Study:
    """Parses and validates a study: a file name, JSON text or a dict. The base scene is parsed by the
    C++ scene parser, every varied path is tried on it (with its first value) and the model is built
    once to resolve surface-node samples. Raises InvalidInput / IoError naming the JSON path at fault.
    settings: overrides of the file's declared settings (samples.count, samples.method, seed, batch,
    max_runs; docs/parameters.md): a StudySettings, a dict {name: value} or "NAME=VALUE,..." text."""
    origin = "study"
    if isinstance(study, (str, os.PathLike)) and not os.fspath(study).lstrip().startswith("{"):
        p = Path(study)
        origin = str(study)
        try:
            text = p.read_text()
        except OSError as e:
            raise IoError(f"{study}: cannot read the study file ({e.strerror})") from None
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as e:
            raise InvalidInput(f"{study}: invalid JSON at line {e.lineno}, column {e.colno}: {e.msg}") from None
        base = p.resolve().parent
    elif isinstance(study, dict):
        doc = copy.deepcopy(study)
        base = Path(base_dir or ".").resolve()
    elif isinstance(study, str):
        try:
            doc = json.loads(study)
        except json.JSONDecodeError as e:
            raise InvalidInput(f"study: invalid JSON at line {e.lineno}, column {e.colno}: {e.msg}") from None
        base = Path(base_dir or ".").resolve()
    else:
        raise InvalidInput(f"study: expected a file name, JSON text or a dict; got a {type(study).__name__}")
    w = _Where(origin)
    check_keys(w, doc, extra=SETTINGS_KEYS)  # every declared key of scene/study_schema.hpp

    # The base scene: a file (relative to the study) or an inline object.
    sc = doc["scene"]
    try:
        if isinstance(sc, str):
            f = Path(sc) if Path(sc).is_absolute() else base / sc
            scene = scene_document(f)
        elif isinstance(sc, dict):
            scene = scene_document(sc, base, f"{origin}: scene")
        else:
            w.fail("scene", "expected a scene file name or an inline scene object")
    except (InvalidInput, IoError) as e:
        if str(e).startswith(origin + ":"):
            raise
        raise type(e)(f"{origin}: scene: {e}") from None

    scene = without_key_times(scene)  # a study records fields at outputs.fields.times only
    fixed = doc.get("set", {})
    for path, value in fixed.items():
        try:
            scene = apply_overrides(scene, [(path, value)])
        except InvalidInput as e:
            w.fail(f"set.{path}", str(e))
    if fixed:  # all at once: a new duration and new key times are checked together
        try:
            scene = json.loads(_medspring.scene_json(json.dumps(scene), str(base), "scene"))
        except InvalidInput as e:
            w.fail("set", str(e))

    vary_doc = doc.get("vary", [])
    vary = [_parse_vary(w, k, e) for k, e in enumerate(vary_doc)]
    paths = [v.path for v in vary]
    for k, p in enumerate(paths):
        if p in paths[:k]:
            w.fail(f"vary[{k}].path", f"'{p}' is varied twice")

    # The declared keys (samples, seed, batch, max_runs): read and checked by their declaration.
    declared = study_settings_from_json(json.dumps({k: doc[k] for k in SETTINGS_KEYS if k in doc}), origin)
    declared, overridden = _apply_settings(declared, settings, origin)
    samples = doc.get("samples", {})
    count_given = "count" in samples or "samples.count" in overridden
    has_sampled = any(v.sampled for v in vary)
    count = declared.samples.count
    if count_given and not has_sampled:
        w.fail("samples.count", "the study varies nothing by sampling (uniform, choice, surface_node, ...)")
    if has_sampled and not count_given:
        w.fail("samples", "sampled quantities need samples.count")
    method = declared.samples._param_text("method")
    seed = declared.seed

    outputs = doc.get("outputs", {})
    metrics = outputs.get("metrics", list(METRICS))
    fields = outputs.get("fields", None)
    field_times: list = []
    field_dtype = "float64"
    if fields is not None:
        for k, t in enumerate(fields["times"]):
            if not t <= scene["duration"]:
                w.fail(f"outputs.fields.times[{k}]", f"{t} ms is outside the scene's [0, {scene['duration']}] ms")
            field_times.append(float(t))
        field_dtype = fields.get("dtype", "float64")
    batch, max_runs = declared.batch, declared.max_runs
    name = doc.get("name", Path(origin).stem if origin != "study" else "study")

    listed = [v for v in vary if not v.sampled]
    st = Study(
        name=name,
        description=str(doc.get("description", "")),
        origin=origin,
        scene=scene,
        vary=vary,
        count=count if has_sampled else 1,
        method=method,
        seed=seed,
        metrics=list(metrics),
        field_times=field_times,
        field_dtype=field_dtype,
        batch=batch,
        max_runs=max_runs,
        settings=declared,
        grid_shape=tuple(len(v.values) for v in listed),
    )
    resolve_model(st, w)
    return st


def resolve_model(st: Study, w: _Where) -> None:
    """Builds the base model (in this process, cached) and tries every varied path with one value."""
    from ..scenes import scene_runner

    try:
        model = scene_runner().model(json.dumps(st.scene), "/", f"{st.origin}: scene")
    except InvalidInput as e:
        raise InvalidInput(f"{st.origin}: scene: {e}") from None
    st.num_surface_nodes = int(model["num_surface_nodes"])
    st.surface = Surface(model["rest_surface"], model["faces"])
    if st.num_runs == 0:
        w.fail("vary", "the study has no runs")
    # Every varied path on its own, with its first (or a sampled) value: unknown paths fail here.
    for v in st.vary:
        value = v.values[0] if v.values else v.from_unit(np.full(v.dims, 0.5), st.surface)
        try:
            d = apply_overrides(st.scene, [(v.path, value)])
            _medspring.scene_json(json.dumps(d), "/", "scene")
        except InvalidInput as e:
            w.fail(f"{v.where}.path", f"'{v.path}': {e}")
        if v.kind == "values":
            for k, value in enumerate(v.values[1:], 1):
                try:
                    d = apply_overrides(st.scene, [(v.path, value)])
                    _medspring.scene_json(json.dumps(d), "/", "scene")
                except InvalidInput as e:
                    w.fail(f"{v.where}.values[{k}]", str(e))
