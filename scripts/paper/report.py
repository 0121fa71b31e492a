#!/usr/bin/env python3
"""Renders the paper's report (report.md) from the study's results.json (used by `medspring paper`).

usage: report.py RESULTS.json REPORT.md

The text is the Jinja2 template report.md.j2 beside this file. Every sentence that states a finding is
conditioned on the measured values: the findings are worked out here (findings()), from the results
alone, and the template words each one by its outcome. Importable: render(results) -> str.
"""
import json
import math
import os
import sys

import jinja2

HERE = os.path.dirname(os.path.abspath(__file__))


def fixed(x, digits=3):
    if x is None or not isinstance(x, (int, float)) or not math.isfinite(x):
        return "—"
    return f"{x:.{digits}f}"


def sig(x, digits=3):
    if x is None or not isinstance(x, (int, float)) or not math.isfinite(x):
        return "—"
    return f"{x:.{digits}g}"


def value(run, key):
    """A summary value of a run, inf where the run has none (a return that never happened)."""
    v = run["summary"].get(key)
    return math.inf if v is None else float(v)


def find(results, set_, file, literal=False):
    for r in results["runs"]:
        if r["set"] == set_ and r["file"] == file and bool(r.get("literal")) == literal:
            return r
    return None


def rel_diff(a, b):
    """|a - b| / max(|a|, |b|), 0 when both are 0."""
    m = max(abs(a), abs(b))
    return 0.0 if m == 0 else abs(a - b) / m


def findings(results):
    """Every finding the report states, computed from the results."""
    primary = results["meta"]["primary"]
    runs = results["runs"]
    f = {"primary": primary}
    kidney = [r for r in runs if r["group"] == "kidney" and not r.get("literal")]
    # §7.1: back in shape, and nonlinear never softer than linear
    f["kidney_back"] = all(value(r, "final_max_disp_mm") < 1e-3 and value(r, "return_ms") < 200 for r in kidney)
    f["kidney_not_back"] = [f"{r['set']} {r['label']}" for r in kidney
                            if not (value(r, "final_max_disp_mm") < 1e-3 and value(r, "return_ms") < 200)]
    softer = []
    gaps = {}
    for r in kidney:
        if r["nonlinear"]:
            lin = find(results, r["set"], r["file"].rsplit("_", 1)[0] + "_linear")
            if lin is None:
                continue
            nl, li = value(r, "contact_hold_mm"), value(lin, "contact_hold_mm")
            if nl > li:
                softer.append(f"{r['set']} {r['label']}")
            if r["set"] == primary:
                gaps[r["force_N"]] = (li - nl) / li if li > 0 else 0.0
    f["kidney_nonlinear_softer"] = softer
    forces = sorted(gaps)
    f["kidney_gap_by_force"] = [(F, gaps[F]) for F in forces]
    f["kidney_gap_grows"] = len(forces) >= 2 and all(gaps[a] < gaps[b] for a, b in zip(forces, forces[1:]))
    ph = find(results, "phantom", "kidney_1.0N_nonlinear")
    f["prototype"] = None
    if ph is not None:
        proto = {"contact": 5.08, "atom": 1.71, "return": 31.0}
        got = {"contact": value(ph, "contact_hold_mm"), "atom": value(ph, "atom_hold_mm"),
               "return": value(ph, "return_ms")}
        f["prototype"] = {"got": got, "proto": proto,
                          "agree": all(rel_diff(got[k], proto[k]) <= 0.1 for k in ("contact", "atom"))}
    # §7.2: the vessel
    vl = find(results, primary, "vessel_light_nonlinear")
    vs = find(results, primary, "vessel_strong_nonlinear")
    vsl = find(results, primary, "vessel_strong_linear")
    vlf = find(results, primary, "vessel_light_nonlinear_local")
    f["vessel_strong_bends_more"] = vs is not None and vl is not None and \
        value(vs, "atom_hold_mm") > value(vl, "atom_hold_mm")
    if vs is not None and vsl is not None:
        d = rel_diff(value(vs, "atom_hold_mm"), value(vsl, "atom_hold_mm"))
        f["vessel_law_diff"] = d
        f["vessel_law_differ_little"] = d < 0.05
        f["vessel_nonlinear_softer"] = value(vs, "atom_hold_mm") > value(vsl, "atom_hold_mm") * (1 + 1e-9)
    else:
        f["vessel_law_diff"] = None
        f["vessel_law_differ_little"] = False
        f["vessel_nonlinear_softer"] = False
    f["local_dent_small"] = vlf is not None and \
        value(vlf, "local_hold_mm") < 0.2 * vlf["facts"].get("contact_radius_mm", math.inf)
    # D-9: the visibility filter on the kidney
    k = find(results, primary, "kidney_1.0N_nonlinear")
    f["visibility"] = k["facts"] if k is not None else {}
    # the paper-literal set next to the unit-consistent default
    lit = []
    for r in runs:
        if r.get("literal"):
            base = find(results, r["set"], r["file"])
            if base is None:
                continue
            c_lit, c_def = value(r, "contact_hold_mm"), value(base, "contact_hold_mm")
            key = "atom_hold_mm" if r["group"] == "vessel" else "contact_hold_mm"
            d_lit, d_def = value(r, key), value(base, key)
            lit.append({
                "group": r["group"], "label": r["label"], "base_label": base["label"],
                "measure": "loaded atom" if r["group"] == "vessel" else "contact node",
                "lit": d_lit, "def": d_def, "contact_lit": c_lit, "contact_def": c_def,
                "change": (d_lit - d_def) / d_def if d_def > 0 else 0.0,
                "return_lit": value(r, "return_ms"), "return_def": value(base, "return_ms"),
                "substeps_lit": r["facts"].get("substeps_per_update", math.nan),
                "substeps_def": base["facts"].get("substeps_per_update", math.nan),
                "step_lit": r["facts"].get("effective_step_ms", math.nan),
                "step_def": base["facts"].get("effective_step_ms", math.nan),
                "dt_rest": base["facts"].get("dt_safe_rest_ms", math.nan),
                "mode_def": results["parameters"]["kidney" if r["group"] == "kidney" else "vessel"]["duffing_mode"],
            })
    for x in lit:
        x["softer"] = x["lit"] > x["def"] * (1 + 1e-6)
        x["stiffer"] = x["lit"] < x["def"] * (1 - 1e-6)
        x["same"] = rel_diff(x["lit"], x["def"]) < 0.01
        x["return_same"] = abs(x["return_lit"] - x["return_def"]) <= 1.0 or \
            (math.isinf(x["return_lit"]) and math.isinf(x["return_def"]))
        x["return_longer"] = x["return_lit"] > x["return_def"] + 1.0
        x["more_substeps"] = x["substeps_lit"] > x["substeps_def"] * (1 + 1e-6)
        x["fewer_substeps"] = x["substeps_lit"] < x["substeps_def"] * (1 - 1e-6)
    f["literal"] = lit
    # Tables I and II
    t = results.get("tables")
    f["timing"] = None
    if t:
        cases = {(c["model"], c["nonlinear"], c["local"]): c for c in t["cases"]}

        def ratio(a, b):
            return cases[a]["median_us"] / cases[b]["median_us"]

        def noise(a, b):
            return max(cases[a]["round_spread"], cases[b]["round_spread"])

        smrm_nl, smrm_l = ("SMRM", True, "off"), ("SMRM", False, "off")
        ms_nl, ms_l = ("MS", True, "off"), ("MS", False, "off")
        f["timing"] = {
            "smrm_law_equal": abs(ratio(smrm_nl, smrm_l) - 1) <= noise(smrm_nl, smrm_l),
            "smrm_law_ratio": ratio(smrm_nl, smrm_l),
            "ms_more_substeps": cases[ms_nl]["substeps_per_update"] > cases[ms_l]["substeps_per_update"],
            "ms_substeps_nl": cases[ms_nl]["substeps_per_update"],
            "ms_substeps_l": cases[ms_l]["substeps_per_update"],
            "smrm_substeps": cases[smrm_nl]["substeps_per_update"],
            "smrm_springs": cases[smrm_nl]["springs"],
            "all_hold": all(c["holds"] for c in t["ordering_checks"]),
            "failed": [c["claim"] for c in t["ordering_checks"] if c["verdict"] == "no"],
        }
    return f


def render(results):
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(HERE), undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True)
    env.filters["fixed"] = fixed
    env.filters["sig"] = sig
    env.filters["pct"] = lambda x, d=1: fixed(100 * x, d)
    env.globals["value"] = value
    env.globals["find"] = lambda set_, file, literal=False: find(results, set_, file, literal)
    return env.get_template("report.md.j2").render(r=results, f=findings(results), math=math)


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(argv[1]) as fh:
        results = json.load(fh)
    text = render(results)
    tmp = argv[2] + ".tmp"
    with open(tmp, "w") as fh:
        fh.write(text)
    os.replace(tmp, argv[2])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
