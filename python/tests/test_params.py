"""Parameters declared once (core/params.hpp): every declared field of HybridSettings, StepSettings and
DuffingSettings is a Python property and keyword argument, and the same name set from Python, through a
scene file and back, keeps its value."""

import json
import math

import pytest

import medspring as ms

m = ms._medspring


def changed(spec, value):
    """A valid value of the declared field different from `value`."""
    if isinstance(value, bool):
        return not value
    if isinstance(value, list):
        return [1, 3, 4]
    if isinstance(value, int) and not hasattr(value, "name"):
        up = value + 1
        return up if up <= spec["hi"] else value - 1
    if isinstance(value, float):
        up = value * 1.25 + 0.125
        ok = up < spec["hi"] if spec["hi_open"] else up <= spec["hi"]
        return up if ok else value * 0.5
    # an enum: another of its values
    members = list(type(value).__members__.values())
    return members[(members.index(value) + 1) % len(members)]


def norm(value):
    return str(value).replace("_", "").lower() if isinstance(value, str) else value


def as_json(value):
    return str(value).split(".")[-1] if hasattr(value, "name") and not isinstance(value, (bool, int)) else value


@pytest.mark.parametrize("cls", [m.HybridSettings, m.StepSettings, m.DuffingSettings])
def test_every_declared_field_is_a_keyword_and_property(cls):
    specs = cls._params
    assert len(specs) >= 4
    default = cls()
    for spec in specs:
        name = spec["name"]
        value = getattr(default, name)
        if isinstance(value, m.DuffingSettings):
            continue  # nested: its own fields are checked with DuffingSettings
        new = changed(spec, value)
        obj = cls(**{name: new})
        assert getattr(obj, name) == new, name
        assert getattr(cls(), name) == value, name  # the default is untouched
        assert spec["doc"] in getattr(cls, name).__doc__
    with pytest.raises(TypeError, match="unknown field"):
        cls(no_such_field=1)


def test_hybrid_and_step_fields_round_trip_through_a_scene_file():
    hybrid, step = m.HybridSettings(), m.StepSettings()
    params, integrator = {}, {}
    for obj, out in ((hybrid, params), (step, integrator)):
        for spec in type(obj)._params:
            value = getattr(obj, spec["name"])
            if isinstance(value, m.DuffingSettings):
                duffing = {}
                for d in m.DuffingSettings._params:
                    new = changed(d, getattr(value, d["name"]))
                    setattr(value, d["name"], new)  # nested by reference
                    duffing[d["key"]] = as_json(new)
                out[spec["key"]] = duffing
                continue
            new = changed(spec, value)
            setattr(obj, spec["name"], new)
            out[spec["key"]] = as_json(new)
    doc = {"model": {"kind": "hybrid", "source": {"phantom": "kidney"}, "parameters": params},
           "integrator": integrator, "duration": 10}
    back = json.loads(m.scene_json(json.dumps(doc)))
    got_params, got_integrator = back["model"]["parameters"], back["integrator"]
    for spec in m.HybridSettings._params:
        want = getattr(hybrid, spec["name"])
        got = got_params[spec["key"]]
        if isinstance(want, m.DuffingSettings):
            for d in m.DuffingSettings._params:
                w = as_json(getattr(want, d["name"]))
                assert norm(got[d["key"]]) == norm(w), d["name"]
        elif isinstance(want, float):
            assert math.isclose(got, want, rel_tol=0, abs_tol=0), spec["name"]
        else:
            assert got == as_json(want), spec["name"]
    for spec in m.StepSettings._params:
        want = as_json(getattr(step, spec["name"]))
        got = got_integrator[spec["key"]]
        assert norm(got) == norm(want), spec["name"]


@pytest.mark.parametrize("cls", [m.SurfaceBodyParams, m.SmrmSettings, m.LocalOptions, m.ContactSettings])
def test_surface_smrm_local_and_contact_fields_are_keywords_and_properties(cls):
    test_every_declared_field_is_a_keyword_and_property(cls)


def _perturbed(obj):
    """Changes every declared field of obj (nested DuffingSettings by reference) and returns the scene
    file's object of the fields a file holds."""
    out = {}
    for spec in type(obj)._params:
        value = getattr(obj, spec["name"])
        if isinstance(value, m.DuffingSettings):
            out[spec["key"]] = _perturbed(value)
            continue
        new = changed(spec, value)
        setattr(obj, spec["name"], new)
        if not spec["derived"]:
            out[spec["key"]] = obj._param_text(spec["name"]) if hasattr(new, "name") else new
    return out


def _expect_same(obj, got):
    for spec in type(obj)._params:
        if spec["derived"]:
            assert spec["key"] not in got, spec["name"]  # set by the program, never in a file
            continue
        want = getattr(obj, spec["name"])
        if isinstance(want, m.DuffingSettings):
            _expect_same(want, got[spec["key"]])
        elif hasattr(want, "name") and not isinstance(want, (bool, int)):  # an enum
            assert got[spec["key"]] == obj._param_text(spec["name"]), spec["name"]
        else:
            assert got[spec["key"]] == want, spec["name"]


def test_surface_smrm_local_and_contact_fields_round_trip_through_scene_files():
    surface, local, contact = m.SurfaceBodyParams(), m.LocalOptions(), m.ContactSettings()
    tool = {"shape": "sphere", "radius": 8, "path": [{"t": 0, "position": [0, 0, 60]}]}
    doc = {"model": {"kind": "surface", "source": {"phantom": "kidney"}, "parameters": _perturbed(surface)},
           "local": _perturbed(local), "contact": _perturbed(contact), "tools": [tool], "duration": 10}
    back = json.loads(m.scene_json(json.dumps(doc)))
    _expect_same(surface, back["model"]["parameters"])
    _expect_same(local, back["local"])
    _expect_same(contact, back["contact"])

    smrm = m.SmrmSettings()
    doc = {"model": {"kind": "smrm", "source": {"phantom": {"name": "vessel", "path": "straight_x"}},
                     "parameters": _perturbed(smrm)}, "duration": 10}
    assert smrm.bending == m.BendingMode.Constant  # so that k_b is written back
    back = json.loads(m.scene_json(json.dumps(doc)))
    _expect_same(smrm, back["model"]["parameters"])


def test_flat_properties_share_the_nested_settings():
    s = m.SmrmSettings(k_cl=0.3, wall_E=0.8)
    assert s.chain.k == 0.3 and s.wall.E == 0.8
    s.chain = m.ChainSettings(k=0.4)
    assert s.k_cl == 0.4
    p = m.SurfaceBodyParams(mass=0.6, k_r=0.01)
    assert p.node.mass == 0.6 and p.node.return_k == 0.01
    lo = m.LocalOptions(stiffness="linearized", patch_nodes=12)
    assert lo.settings.solver.stiffness == m.LocalStiffness.Linearized and lo.settings.patch.count == 12


def test_study_settings_are_declared_keywords_properties_and_json():
    """StudySettings (scene/study_settings.hpp): every field a keyword and property, set_text as the
    command line's --set, and the study file's JSON written and read back by the declaration."""
    names = [spec["name"] for spec in m.StudySettings._params]
    assert names == ["samples", "seed", "batch", "max_runs"]
    assert [spec["name"] for spec in m.StudySamples._params] == ["count", "method"]
    s = m.StudySettings(seed=7, batch=8, max_runs=50, samples=m.StudySamples(count=4, method="latin_hypercube"))
    assert (s.seed, s.batch, s.max_runs, s.samples.count) == (7, 8, 50, 4)
    assert s.samples.method == m.SampleMethod.LatinHypercube
    doc = json.loads(m.study_settings_json(s))
    assert doc == {"samples": {"count": 4, "method": "latin_hypercube"}, "seed": 7, "batch": 8, "max_runs": 50}
    back = m.study_settings_from_json(json.dumps(doc), "s.json")
    assert json.loads(m.study_settings_json(back)) == doc
    s.set_text("samples.method", "random")
    assert s.samples.method == m.SampleMethod.Random
    with pytest.raises(m.InvalidInput, match="batch: must be an integer in 1..100000"):
        s.set_text("batch", "0")
    with pytest.raises(m.InvalidInput, match=r"^s.json: samples.count: must be >= 1 \(got 0\)$"):
        m.study_settings_from_json('{"samples": {"count": 0}}', "s.json")
    with pytest.raises(TypeError, match="unknown field"):
        m.StudySettings(no_such_field=1)


def test_fem_case_settings_are_declared_once():
    """FemCaseSettings (scene/study_settings.hpp): the keys of a medspring.study.fem case and the defaults of
    fem_reference, calibrate and `medspring calibrate` are the declaration's."""
    if not hasattr(m, "FemCaseSettings"):
        pytest.skip("built without the FEM layer")
    import inspect

    from medspring.study import fem

    names = [spec["name"] for spec in m.FemCaseSettings._params]
    assert names == ["E_kPa", "nu", "radius", "support_depth", "level"]
    assert fem.CASE_KEYS == tuple(names) + ("support_direction",)
    d = m.FemCaseSettings()
    sig = inspect.signature(fem.calibrate)
    for name in ("E_kPa", "nu", "radius", "support_depth"):
        assert sig.parameters[name].default == getattr(d, name), name
        assert f"{name}: float = {getattr(d, name)}" in m.fem_reference.__doc__, name
    assert f"level: int = {d.level}" in m.fem_reference.__doc__
    assert m.FemCaseSettings(E_kPa=12.0).E_kPa == 12.0
    with pytest.raises(m.InvalidInput, match=r"nu: must be < 0.5 \(got 0.5\)"):
        d.set_text("nu", "0.5")
    with pytest.raises(m.InvalidInput, match=r"level: must be an integer in 1..3 \(got 4\)"):
        d.set_text("level", "4")
