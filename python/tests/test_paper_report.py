"""The paper's report is rendered from its results (scripts/paper/report.py, report.md.j2): every sentence
stating a finding follows the measured values. Rendered here from a committed results.json of a
`medspring paper --quick` run (python/tests/data/paper_results.json) and from altered copies of it: when
a value is changed so that a finding no longer holds, the claim in the text changes."""

import copy
import importlib.util
import json
import math
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
FIXTURE = Path(__file__).resolve().parent / "data" / "paper_results.json"

jinja2 = pytest.importorskip("jinja2")


def report_module():
    spec = importlib.util.spec_from_file_location("paper_report", REPO / "scripts" / "paper" / "report.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


REPORT = report_module()


@pytest.fixture()
def results():
    with open(FIXTURE) as fh:
        return json.load(fh)


def run(results, file, set_="phantom", literal=False):
    for r in results["runs"]:
        if r["file"] == file and r["set"] == set_ and bool(r["literal"]) == literal:
            return r
    raise KeyError(file)


def test_the_measured_results_render_with_their_findings(results):
    text = REPORT.render(results)
    f = REPORT.findings(results)
    assert text.startswith("# MedSpring — the paper reproduced")
    # the fixture's measured findings, stated as measured
    assert f["kidney_back"] and not f["kidney_nonlinear_softer"]
    assert "back in shape after the release" in text
    assert "Nonlinear (hard Duffing) springs never give a larger contact displacement" in text
    assert "Nonlinear springs gave a larger contact displacement" not in text
    assert "## The paper's literal constants next to the unit-consistent default" in text
    assert "Spokes and the visibility filter" in text
    assert "{{" not in text and "{%" not in text


def test_a_nonlinear_kidney_softer_than_its_linear_twin_changes_the_claim(results):
    altered = copy.deepcopy(results)
    nl = run(altered, "kidney_1.0N_nonlinear")
    lin = run(altered, "kidney_1.0N_linear")
    nl["summary"]["contact_hold_mm"] = 1.5 * lin["summary"]["contact_hold_mm"]
    text = REPORT.render(altered)
    assert "Nonlinear (hard Duffing) springs never give a larger contact displacement" not in text
    assert "**Nonlinear springs gave a larger contact displacement than linear ones in: phantom 1.0 N nonlinear**" in text


def test_the_gap_growing_with_the_force_is_measured_not_assumed(results):
    altered = copy.deepcopy(results)
    lin = run(altered, "kidney_0.2N_linear")
    nl = run(altered, "kidney_0.2N_nonlinear")
    big = run(altered, "kidney_1.0N_linear")["summary"]["contact_hold_mm"]
    # 0.2 N: make the nonlinear run 90 % of the linear one, more than at 1.0 N
    nl["summary"]["contact_hold_mm"] = 0.1 * lin["summary"]["contact_hold_mm"]
    assert big > 0
    text = REPORT.render(altered)
    assert "the difference grows with the force" not in text
    assert "the relative difference does not grow with the force here" in text


def test_a_run_that_never_returns_is_reported(results):
    altered = copy.deepcopy(results)
    run(altered, "kidney_0.2N_linear")["summary"]["return_ms"] = None  # never back within 1e-3 mm
    text = REPORT.render(altered)
    assert "back in shape after the release" not in text
    assert "**not every run returns within 1e-3 mm of rest in 200 ms** (phantom 0.2 N linear" in text


def test_the_vessel_laws_differing_little_is_conditioned(results):
    base = REPORT.render(results)
    assert "Linear and nonlinear chains differ little here" in base  # as measured (D-3 strains are small)
    stiffer = copy.deepcopy(results)
    s = run(stiffer, "vessel_strong_nonlinear")
    s["summary"]["atom_hold_mm"] = 0.5 * run(stiffer, "vessel_strong_linear")["summary"]["atom_hold_mm"]
    text = REPORT.render(stiffer)
    assert "differ little" not in text
    assert "Linear and nonlinear chains differ by 50.0 %" in text
    softer = copy.deepcopy(results)
    s = run(softer, "vessel_strong_nonlinear")
    s["summary"]["atom_hold_mm"] = 2.0 * run(softer, "vessel_strong_linear")["summary"]["atom_hold_mm"]
    text = REPORT.render(softer)
    assert "**The nonlinear chain bent more than the linear one**" in text


def test_the_strong_force_bending_more_is_conditioned(results):
    altered = copy.deepcopy(results)
    light = run(altered, "vessel_light_nonlinear")
    light["summary"]["atom_hold_mm"] = 10 * run(altered, "vessel_strong_nonlinear")["summary"]["atom_hold_mm"]
    text = REPORT.render(altered)
    assert "**The strong force did not bend the vessel more than the light one**" in text


def test_the_literal_constants_paragraph_follows_the_values(results):
    f = REPORT.findings(results)
    assert {x["group"] for x in f["literal"]} == {"kidney", "vessel"}
    for factor, word in ((1.5, "softer"), (0.5, "stiffer")):
        altered = copy.deepcopy(results)
        lit = run(altered, "kidney_1.0N_nonlinear", literal=True)
        lit["summary"]["contact_hold_mm"] = factor * run(altered, "kidney_1.0N_nonlinear")["summary"]["contact_hold_mm"]
        text = REPORT.render(altered)
        assert f"On the kidney (1.0 N nonlinear) the literal constants are {word}" in text
    altered = copy.deepcopy(results)
    lit = run(altered, "kidney_1.0N_nonlinear", literal=True)
    lit["facts"]["substeps_per_update"] = 4 * run(altered, "kidney_1.0N_nonlinear")["facts"]["substeps_per_update"]
    lit["summary"]["return_ms"] = run(altered, "kidney_1.0N_nonlinear")["summary"]["return_ms"] + 50
    text = REPORT.render(altered)
    assert "The literal constants need more sub-steps under the held force" in text
    assert "The return to rest takes longer with the literal constants" in text


def test_the_visibility_filter_sentence_follows_the_facts(results):
    altered = copy.deepcopy(results)
    facts = run(altered, "kidney_1.0N_nonlinear")["facts"]
    facts.update(visibility_filtered=True, visibility_rejected=17, visibility_fallbacks=0, spokes=700)
    text = REPORT.render(altered)
    assert "Here 17 candidate(s) left the organ" in text
    facts.update(visibility_rejected=0)
    assert "No candidate left the organ: the filter changed nothing" in REPORT.render(altered)
    facts.update(visibility_filtered=False)
    assert "The filter did not run" in REPORT.render(altered)


def test_a_failed_ordering_claim_is_reported(results):
    altered = copy.deepcopy(results)
    c = altered["tables"]["ordering_checks"][2]
    c.update(holds=False, verdict="no", ratio=0.5)
    text = REPORT.render(altered)
    assert "Every ordering claim of the paper holds here" not in text
    assert f"**Not every ordering claim holds here: {c['claim']}.**" in text


def test_findings_are_a_function_of_the_results_alone(results):
    # the same results give the same text (no clock, no machine state read while rendering)
    assert REPORT.render(results) == REPORT.render(copy.deepcopy(results))
    assert not math.isnan(REPORT.findings(results)["vessel_law_diff"])


ms = pytest.importorskip("medspring")


@pytest.mark.skipif(not getattr(ms._medspring, "has_paper", False), reason="built without the paper layer")
def test_the_same_study_runs_from_python(tmp_path, results):
    out = tmp_path / "paper"
    got = ms.paper.run(out, quick=True, tree=False, timing=False)
    assert json.loads((out / "results.json").read_text()) == got
    assert (out / "report.md").read_text() == ms.paper.render_report(got)
    assert got["meta"]["primary"] == "phantom" and got["tables"] is None and got["tree"] is None
    assert len(got["runs"]) == 14
    # the same runs as `medspring paper --quick` (the fixture): the engine is deterministic
    for mine in got["runs"]:
        theirs = run(results, mine["file"], literal=mine["literal"])
        for key in ("contact_hold_mm", "atom_hold_mm", "return_ms", "updates", "substeps"):
            assert mine["summary"][key] == pytest.approx(theirs["summary"][key], rel=1e-12), (mine["file"], key)
    f = ms.paper.findings(got)
    assert f["kidney_back"] and not f["kidney_nonlinear_softer"]
    with pytest.raises(ms.InvalidInput, match="not an empty folder"):
        ms.paper.run(out, quick=True, tree=False, timing=False)
