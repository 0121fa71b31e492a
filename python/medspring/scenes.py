"""Scenes from Python, in-process: load a scene (file, JSON text or dict), override parameters by their
JSON path, run it on the C++ engine and get the summary metrics and surface displacement fields.

    import medspring as ms
    out = ms.run_scene("scenes/phantom/kidney_1.0N_nonlinear.json",
                       overrides={"loads[0].magnitude": 0.5, "model.parameters.k_surf": 0.08},
                       field_times=[500.0])
    out["summary"]["contact_hold_mm"], out["fields"].shape      # (1, 458, 3), mm

The model is built once per thread and scene `model` section and reused by later runs that change only
loads, integrator, duration or local settings (SceneRunner); the run itself releases the GIL.
"""

from __future__ import annotations

import copy
import json
import os
import re
import threading
from pathlib import Path
from typing import Any, Iterable, Mapping

from . import _medspring
from ._medspring import InvalidInput

__all__ = ["scene_document", "set_path", "get_path", "run_scene", "scene_runner", "parse_path", "without_key_times"]

_local = threading.local()

_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")

# Keys of a load that pick its node / its direction: setting one removes the others.
_SITE_KEYS = ("node", "point", "ring", "spoke")


def scene_runner() -> "_medspring.SceneRunner":
    """This thread's SceneRunner (models are cached per runner; a runner is not shared by threads)."""
    runner = getattr(_local, "runner", None)
    if runner is None:
        runner = _local.runner = _medspring.SceneRunner()
    return runner


def scene_document(scene: Any, base_dir: str | os.PathLike | None = None, origin: str | None = None) -> dict:
    """The scene as a JSON document (dict) with every default filled in and every file path absolute,
    validated by the C++ parser. `scene`: a path of a scene file, JSON text or a dict (relative file
    names against base_dir, default the current folder). Raises InvalidInput / IoError naming the JSON
    path at fault."""
    if isinstance(scene, Mapping):
        text = json.dumps(scene)
        return json.loads(_medspring.scene_json(text, str(base_dir or "."), origin or "scene"))
    if isinstance(scene, (str, os.PathLike)):
        s = os.fspath(scene)
        if s.lstrip().startswith("{"):
            return json.loads(_medspring.scene_json(s, str(base_dir or "."), origin or "scene"))
        return json.loads(_medspring.load_scene_json(Path(s)))
    raise InvalidInput(f"scene: expected a file name, JSON text or a dict; got a {type(scene).__name__}")


def parse_path(path: str) -> list:
    """'loads[0].direction' -> ['loads', 0, 'direction']. Raises InvalidInput on bad syntax."""
    if not isinstance(path, str) or not path:
        raise InvalidInput(f"parameter path: expected text like 'loads[0].magnitude'; got {path!r}")
    out: list = []
    for part in path.split("."):
        m = _TOKEN.match(part)
        if not m:
            raise InvalidInput(f"parameter path '{path}': cannot read '{part}' (expected key or key[i])")
        out.append(m.group(1))
        out.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return out


def _walk(doc: Any, tokens: list, path: str, create_last: bool):
    node = doc
    for depth, t in enumerate(tokens[:-1]):
        here = ".".join(str(x) for x in tokens[: depth + 1])
        if isinstance(t, int):
            if not isinstance(node, list) or t >= len(node):
                size = len(node) if isinstance(node, list) else 0
                raise InvalidInput(f"parameter path '{path}': no element [{t}] (the scene has {size})")
        elif not isinstance(node, dict) or t not in node:
            raise InvalidInput(f"parameter path '{path}': the scene has no '{here}'")
        node = node[t]
    last = tokens[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or last >= len(node):
            raise InvalidInput(f"parameter path '{path}': no element [{last}]")
    elif not isinstance(node, dict):
        raise InvalidInput(f"parameter path '{path}': '{tokens[-2]}' is not an object")
    elif not create_last and last not in node:
        raise InvalidInput(f"parameter path '{path}': the scene has no such parameter")
    return node, last


def get_path(doc: dict, path: str):
    """The value at a parameter path of a scene document."""
    node, last = _walk(doc, parse_path(path), path, create_last=False)
    return node[last]


def set_path(doc: dict, path: str, value) -> None:
    """Sets a parameter of a scene document in place. A new key is allowed (the C++ parser rejects
    unknown ones, naming them); setting a load's node / point / ring+spoke removes the other site keys,
    and a direction other than "towards_atom" removes its `atom`."""
    tokens = parse_path(path)
    node, last = _walk(doc, tokens, path, create_last=True)
    if isinstance(node, dict) and len(tokens) >= 3 and tokens[0] == "loads":
        if last in _SITE_KEYS:
            keep = ("ring", "spoke") if last in ("ring", "spoke") else (last,)
            for k in _SITE_KEYS:
                if k not in keep:
                    node.pop(k, None)
        if last == "direction" and value != "towards_atom":
            node.pop("atom", None)
    if hasattr(value, "tolist"):
        value = value.tolist()
    node[last] = value


def apply_overrides(doc: dict, overrides: Mapping[str, Any] | Iterable | None) -> dict:
    """A copy of the scene document with every (path, value) of overrides set."""
    out = copy.deepcopy(doc)
    if overrides:
        items = overrides.items() if isinstance(overrides, Mapping) else overrides
        for path, value in items:
            set_path(out, path, value)
    return out


def without_key_times(doc: dict) -> dict:
    """A shallow copy of a scene document whose record.key_times is empty: runs from Python record
    frames only at their field_times, so the scene's own key times (which must lie within its duration)
    are dropped before a duration is overridden."""
    out = dict(doc)
    if isinstance(out.get("record"), dict):
        out["record"] = dict(out["record"], key_times=[])
    return out


def run_scene(
    scene: Any,
    overrides: Mapping[str, Any] | None = None,
    field_times: Iterable[float] = (),
    fields: bool = True,
    base_dir: str | os.PathLike | None = None,
    origin: str = "scene",
) -> dict:
    """Runs a scene in this process (GIL released while it runs) and returns a dict: summary (metrics:
    contact_peak_mm, contact_hold_mm, max_disp_peak_mm, atom_hold_mm, local_hold_mm, return_ms,
    final_max_disp_mm, warnings, substeps, updates, wall_seconds, median_update_us), load_node,
    load_force (N), field_times (ms of the frames returned), fields ((T, S, 3) surface displacement,
    mm; with fields=True), build_seconds, run_seconds, model_built.

    scene: file name, JSON text, dict or an already expanded document (scene_document); overrides:
    {"loads[0].magnitude": 0.5, ...}. Raises InvalidInput naming the parameter path at fault."""
    doc = scene if isinstance(scene, dict) else scene_document(scene, base_dir, origin)
    doc = apply_overrides(without_key_times(doc), overrides)
    times = [float(t) for t in field_times]
    return scene_runner().run(json.dumps(doc), str(base_dir or "."), origin, times, fields)
