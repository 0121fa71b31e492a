#!/usr/bin/env python3
"""Summary of `scripts/gpu-check.sh full` (docs/gpu.md): reads OUT/stages.tsv, OUT/gpu-bench/gpu_bench.json
and the GoogleTest XML files in OUT/xml, writes OUT/summary.json and OUT/summary.md with the figures of
issue 21's table and targets, each test's result and its recorded properties. Standard library only (the
GPU machine has Python but no registry). Missing inputs are reported as missing, never invented.

    python3 scripts/gpu_summary.py OUT
"""

import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

# Issue 21's targets (H100, one bench run): (what, test on the bench JSON).
TARGETS = [  # (what, nodes, precision, limit in µs per substep)
    ("1M-node tube fp64 <= 100 us per substep", 1_000_000, "fp64", 100),
    ("1M-node tube fp32 <= 60 us per substep", 1_000_000, "fp32", 60),
    ("16M-node tube fp64 <= 1.5 ms per substep", 16_000_000, "fp64", 1500),
    ("1,200-node tube <= 6 us per substep", 1_200, "fp64", 6),
]


def near(nodes, target):
    return abs(nodes - target) <= 0.1 * target


def load_bench(out):
    p = out / "gpu-bench" / "gpu_bench.json"
    if not p.exists():
        return None
    try:
        return json.loads(p.read_text())
    except json.JSONDecodeError as e:
        return {"error": f"{p}: {e}"}


def load_tests(out):
    tests = []
    for x in sorted((out / "xml").glob("*.xml")):
        try:
            root = ET.parse(x).getroot()
        except ET.ParseError as e:
            tests.append({"file": x.name, "name": "(unreadable)", "result": f"xml error: {e}"})
            continue
        for tc in root.iter("testcase"):
            name = f"{tc.get('classname')}.{tc.get('name')}"
            if tc.find("failure") is not None:
                result = "failed"
            elif tc.find("skipped") is not None or tc.get("result") == "skipped":
                result = "skipped"
            else:
                result = "passed"
            props = {p.get("name"): p.get("value") for p in tc.iter("property")}
            props.update({k: v for k, v in tc.attrib.items() if k not in ("name", "classname", "status", "result",
                                                                           "time", "timestamp", "file", "line")})
            tests.append({"file": x.name, "name": name, "result": result, "seconds": float(tc.get("time", 0) or 0),
                          "properties": props})
    return tests


def main(argv):
    out = Path(argv[1] if len(argv) > 1 else ".")
    stages = []
    st = out / "stages.tsv"
    if st.exists():
        for line in st.read_text().splitlines():
            name, rc, seconds = (line.split("\t") + ["", "", ""])[:3]
            stages.append({"stage": name, "rc": int(rc) if rc.lstrip("-").isdigit() else rc,
                           "seconds": float(seconds or 0)})
    bench = load_bench(out)
    tests = load_tests(out)
    summary = {"stages": stages, "bench": bench, "tests": tests}

    md = ["# scripts/gpu-check.sh full", ""]
    md += ["| stage | exit | seconds |", "|---|---|---|"]
    md += [f"| {s['stage']} | {s['rc']} | {s['seconds']:.0f} |" for s in stages]
    md.append("")
    table, checks = [], []
    if bench and "tubes" in bench:
        dev = bench.get("device", {})
        copy = bench.get("copy_bandwidth_gbs")
        md += [f"Device: {dev.get('name')} (compute {dev.get('compute')}, {dev.get('multiprocessors')} SMs, driver "
               f"{dev.get('driver')}, runtime {dev.get('runtime')}); copy bandwidth {copy} GB/s.", ""]
        rows = {}
        for t in bench["tubes"]:
            r = rows.setdefault(t["nodes"], {"nodes": t["nodes"]})
            key = t["precision"]
            r[f"gpu_{key}_us"] = t.get(f"gpu_{key}_substep_us")
            r[f"torch_{key}_us"] = t.get(f"torch_{key}_substep_us")
            r[f"frame_{key}_us"] = t.get("gpu_frame_us")
            r[f"fraction_of_copy_{key}"] = t.get("fraction_of_copy")
            if t.get("cpu_substep_us"):
                r["cpu_us"] = t["cpu_substep_us"]
            # The fastest variant of each precision (fp64, fp64c, fp64c-g4, ...: bench --compact --gather).
            base, us = key[:4], t.get(f"gpu_{key}_substep_us")
            if us is not None and (r.get(f"best_{base}_us") is None or us < r[f"best_{base}_us"]):
                r[f"best_{base}_us"], r[f"best_{base}_variant"] = us, key
        table = [rows[n] for n in sorted(rows)]

        def fmt(v, digits=3):
            return "—" if v is None else f"{v:.{digits}g}"

        md += ["| nodes | GPU fp64 µs/substep | GPU fp32 | fastest fp64 (variant) | fastest fp32 (variant) | "
               "PyTorch fp64 | PyTorch fp32 | CPU 1 thread | fp64 of copy bandwidth | step() frame fp64 µs |",
               "|---|---|---|---|---|---|---|---|---|---|"]
        for r in table:
            md.append(f"| {r['nodes']:,} | {fmt(r.get('gpu_fp64_us'))} | {fmt(r.get('gpu_fp32_us'))} | "
                      f"{fmt(r.get('best_fp64_us'))} ({r.get('best_fp64_variant', '—')}) | "
                      f"{fmt(r.get('best_fp32_us'))} ({r.get('best_fp32_variant', '—')}) | "
                      f"{fmt(r.get('torch_fp64_us'))} | {fmt(r.get('torch_fp32_us'))} | {fmt(r.get('cpu_us'))} | "
                      f"{fmt(r.get('fraction_of_copy_fp64'), 2)} | {fmt(r.get('frame_fp64_us'))} |")
        md += ["", "Variants: fp64 = full parameter arrays; c = compact parameters; -gN = N entries gathered at a "
               "time. The targets below take each precision's fastest variant.", ""]

        def t_of(nodes, key):
            for r in table:
                if near(r["nodes"], nodes):
                    return r.get(f"best_{key}_us", r.get(f"gpu_{key}_us"))
            return None

        for what, nodes, key, limit in TARGETS:
            v = t_of(nodes, key)
            checks.append({"target": what, "met": None if v is None else v <= limit, "value_us": v})
        big = [r for r in table if r["nodes"] >= 900_000 and r.get("fraction_of_copy_fp64") is not None]
        if big:
            checks.append({"target": "effective bandwidth >= 70 % of copy at >= 1M nodes",
                           "met": all(r["fraction_of_copy_fp64"] >= 0.7 for r in big)})
        m1 = next((r for r in table if near(r["nodes"], 1_000_000)), None)
        if m1 and m1.get("torch_fp64_us") and m1.get("best_fp64_us"):
            ratio = m1["torch_fp64_us"] / m1["best_fp64_us"]
            checks.append({"target": f">= 8x faster than PyTorch at 1M nodes (fp64: {ratio:.1f}x)", "met": ratio >= 8})
        batch = bench.get("batch", [])
        if batch:
            md += ["| kidneys | precision | kernel | µs/substep | model-substeps/s | step() frame µs |",
                   "|---|---|---|---|---|---|"]
            md += [f"| {b['models']} | {b['precision']} | {b['kernel']} | {fmt(b['substep_us'])} | "
                   f"{b['model_substeps_per_s']:.3g} | {fmt(b['step_frame_us'])} |" for b in batch]
            md.append("")
            best = max((b["model_substeps_per_s"] for b in batch if b["precision"] == "fp64" and b["models"] >= 2000),
                       default=None)
            if best is not None:
                checks.append({"target": f">= 5e7 model-steps/s fp64 with >= 2,000 kidneys (best {best:.3g})",
                               "met": best >= 5e7})
    else:
        md += ["No bench result (gpu-bench/gpu_bench.json missing or unreadable): every GPU figure unmeasured.", ""]
    summary["table"] = table
    summary["targets"] = checks
    if checks:
        md += ["| target | met |", "|---|---|"]
        for c in checks:
            met = "unmeasured" if c["met"] is None else "yes" if c["met"] else "NO"
            md.append(f"| {c['target']} | {met} |")
        md.append("")
    counts = {k: sum(1 for t in tests if t["result"] == k) for k in ("passed", "failed", "skipped")}
    summary["test_counts"] = counts
    md += [f"Tests: {counts['passed']} passed, {counts['failed']} failed, {counts['skipped']} skipped.", ""]
    md += ["| test | result | s | recorded |", "|---|---|---|---|"]
    for t in tests:
        props = ", ".join(f"{k}={v}" for k, v in t.get("properties", {}).items())
        md.append(f"| {t['name']} | {t['result']} | {t.get('seconds', 0):.1f} | {props} |")
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    (out / "summary.md").write_text("\n".join(md) + "\n")
    print("\n".join(md[: min(len(md), 60)]))
    print(f"wrote {out / 'summary.json'} and {out / 'summary.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
