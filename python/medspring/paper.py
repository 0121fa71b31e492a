"""The paper's study from Python: the same experiment set, runs, timing protocol and results as
`medspring paper` (the C++ paper module, src/paper), without the rendered figures.

    import medspring
    results = medspring.paper.run("out/paper", quick=True)      # the results dict (results.json)
    results["tables"]["table1"]["smrm"]["nonlinear"]["measured_median_ms"]
    [r["summary"]["contact_hold_mm"] for r in results["runs"] if r["group"] == "kidney"]

`out` receives results.json, tables.json, report.md (rendered from the results by
scripts/paper/report.py, Jinja2) and scenes/<set>/<name>/summary.json of every run.
render_report(results) renders the report's text from a results dict (any, e.g. an altered one).
"""

from __future__ import annotations

import importlib.util
import json
import os
import sys
from pathlib import Path

from . import _medspring


def scripts_dir() -> Path:
    """The folder of the paper's scripts (render.py, plots.py, report.py, report.md.j2)."""
    env = os.environ.get("MEDSPRING_PAPER_SCRIPTS")
    return Path(env) if env else Path(_medspring.paper_scripts_dir)


def run(out, quick: bool = True, scenes=None, data=None, tree: bool = True, timing: bool = True,
        report: bool = True, accuracy_markdown: str = "") -> dict:
    """Runs the paper's study into the folder `out` (absent or empty) and returns the results dict.

    quick: phantoms only and fewer timed updates (the CLI's --quick; a full run takes minutes);
    scenes: the bundled scene folder (default: the source tree's scenes/); data: the real anatomy
    (default: $MEDSPRING_DATA or the configured folder); tree / timing: the vessel tree runs and
    Tables I and II; report: report.md rendered from the results (needs Jinja2).
    Raises InvalidInput / IoError / Error with the C++ message. Releases the GIL while it runs.
    """
    text = _medspring._paper_run(
        str(out), bool(quick), str(scenes or _medspring.paper_scenes_dir), str(data or ""), bool(tree),
        bool(timing), bool(report), sys.executable, str(scripts_dir()), accuracy_markdown)
    return json.loads(text)


def _report_module():
    spec = importlib.util.spec_from_file_location("medspring_paper_report", scripts_dir() / "report.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def findings(results: dict) -> dict:
    """The findings the report states, worked out from a results dict (scripts/paper/report.py)."""
    return _report_module().findings(results)


def render_report(results: dict) -> str:
    """The report's Markdown rendered from a results dict (scripts/paper/report.md.j2)."""
    return _report_module().render(results)
