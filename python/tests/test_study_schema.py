"""A study file's lists and objects (`vary`, `outputs`, `scene`, `set`, ...) are declared once in C++
(scene/study_schema.hpp, medspring.study_file_schema()): medspring.study checks study files against that
declaration with the JSON path in every error, its metric list is the declared one, and docs/parameters.md
("Study file", "Study metrics") is generated from it (scene_params_tests checks the committed page)."""

import copy

import pytest

import medspring as ms
from conftest import REPO

spec = pytest.importorskip("medspring.study.spec")

KIDNEY = str(REPO / "scenes" / "phantom" / "kidney_1.0N_nonlinear.json")
GOOD = {
    "scene": KIDNEY,
    "vary": [
        {"path": "loads[0].magnitude", "grid": {"from": 0.2, "to": 1.0, "num": 2}},
        {"path": "model.parameters.k_surf", "log_uniform": [0.01, 0.1]},
    ],
    "samples": {"count": 2},
    "outputs": {"metrics": ["contact_hold_mm"], "fields": {"times": [10.0], "dtype": "float32"}},
}


def altered(path, value):
    """GOOD with the key at `path` (a list of keys and indices) set to value (or removed: ...)."""
    doc = copy.deepcopy(GOOD)
    obj = doc
    for k in path[:-1]:
        obj = obj[k]
    if value is ...:
        del obj[path[-1]]
    else:
        obj[path[-1]] = value
    return doc


def refusal(doc):
    w = spec._Where("s.json")
    with pytest.raises(ms.InvalidInput) as e:
        spec.check_keys(w, doc, extra=spec.SETTINGS_KEYS)
    return str(e.value)


def test_a_good_study_passes_the_declared_checks():
    spec.check_keys(spec._Where("s.json"), GOOD, extra=spec.SETTINGS_KEYS)


@pytest.mark.parametrize(
    "path, value, message",
    [
        (["vary", 0, "grid", "step"], 1, "s.json: vary[0].grid.step: unknown key (expected one of from, to, num, log)"),
        (["vary", 0, "grid", "num"], 0, "s.json: vary[0].grid.num: must be >= 1 (got 0)"),
        (["vary", 0, "grid", "num"], 2.5, "s.json: vary[0].grid.num: expected a finite integer; got 2.5"),
        (["vary", 0, "grid", "to"], ..., "s.json: vary[0].grid: missing key 'to'"),
        (["vary", 0, "grid", "log"], "yes", 's.json: vary[0].grid.log: expected true or false; got "yes"'),
        (["vary", 0, "values"], [1, 2], "s.json: vary[0]: give exactly one of values, grid, uniform, log_uniform, "
                                        "integers, choice, surface_node, surface_point, unit_vector (got 2)"),
        (["vary", 1, "log_uniform"], [0, 1], "s.json: vary[1].log_uniform[0]: must be > 0 (got 0.0)"),
        (["vary", 1, "log_uniform"], [2, 1], "s.json: vary[1].log_uniform: needs low < high (got 2.0, 1.0)"),
        (["vary", 1, "log_uniform"], [1], "s.json: vary[1].log_uniform: expected [low, high]; got [1]"),
        (["vary", 1, "path"], ..., "s.json: vary[1]: missing key 'path'"),
        (["vary", 1], {"path": "seed", "surface_node": "all"}, 's.json: vary[1].surface_node: expected "random"; got "all"'),
        (["vary", 1], {"path": "x", "integers": [1.5, 3]}, "s.json: vary[1].integers[0]: expected a finite integer; got 1.5"),
        (["vary", 1], {"path": "x", "choice": []}, "s.json: vary[1].choice: is empty: at least one element is needed"),
        (["vary"], {"path": "x"}, 's.json: vary: expected a list; got {"path": "x"}'),
        (["outputs", "metrics", 0], "contact_hold", "s.json: outputs.metrics[0]: expected one of contact_peak_mm, "),
        (["outputs", "fields", "times", 0], -1, "s.json: outputs.fields.times[0]: must be >= 0 (got -1.0)"),
        (["outputs", "fields", "times"], ..., "s.json: outputs.fields: missing key 'times'"),
        (["outputs", "fields", "dtype"], "float16", 's.json: outputs.fields.dtype: expected "float64" or "float32"; '
                                                   'got "float16"'),
        (["outputs", "plots"], True, "s.json: outputs.plots: unknown key (expected one of metrics, fields)"),
        (["name"], "", 's.json: name: expected non-empty text; got ""'),
        (["set"], [], "s.json: set: expected an object; got []"),
        (["scene"], 3, "s.json: scene: expected a file name or an object; got 3"),
        (["scene"], ..., "s.json: study: missing key 'scene'"),
        (["sead"], 3, "s.json: sead: unknown key (expected one of name, description, scene, set, vary, outputs, "
                      "samples, seed, batch, max_runs)"),
    ],
)
def test_a_key_off_its_declaration_is_refused_naming_its_json_path(path, value, message):
    assert refusal(altered(path, value)).startswith(message)


def test_load_study_checks_the_declaration_before_reading_the_scene():
    doc = altered(["vary", 0, "grid", "num"], 0)
    doc["scene"] = "/no/such/scene.json"  # never read: the declared checks come first
    with pytest.raises(ms.InvalidInput, match=r"^study: vary\[0\]\.grid\.num: must be >= 1 \(got 0\)$"):
        spec.load_study(doc)


def test_the_kinds_and_metrics_are_the_declared_ones():
    schema = ms.study_file_schema()
    metrics = schema["metrics"]
    assert spec.METRICS == tuple(m["name"] for m in metrics if m["by_default"])
    assert spec.TOOL_METRICS == ("tool_peak_force_N", "tool_final_force_N", "tool_peak_penetration_mm")
    assert all(m["unit"] or m["name"] in ("warnings", "substeps") for m in metrics)
    kinds = [k["path"].split(".")[-1] for k in schema["keys"] if k["one_of"] == "kind"]
    assert set(kinds) == set(spec.LISTED_KINDS + spec.SAMPLED_KINDS)
    words = next(k for k in schema["keys"] if k["path"] == "outputs.metrics[]")["words"]
    assert words == [m["name"] for m in metrics]


def test_docs_parameters_md_lists_every_declared_key_and_metric():
    page = (REPO / "docs" / "parameters.md").read_text()
    schema = ms.study_file_schema()
    for k in schema["keys"]:
        assert f"| `{k['path']}` | {k['type']} |" in page, k["path"]
    for m in schema["metrics"]:
        assert f"| `{m['name']}` | number | {m['unit']} |" in page, m["name"]
