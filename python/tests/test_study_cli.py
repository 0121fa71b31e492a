"""The study runner's command line is declared once (C++ scene/study_switches.hpp, read here through
medspring.study_runner_cli()): `python3 -m medspring.study` (argparse) and `medspring study` (CLI11) are
both built from it, and every declared switch is read by the runner. `drift` names every way the three
can part; it is shown to fail on a declaration altered in each of those ways."""

import argparse
import inspect
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import medspring as ms

main_mod = pytest.importorskip("medspring.study.__main__")

PYTHONPATH = str(Path(ms.__file__).resolve().parents[1])
ENV = dict(os.environ, PYTHONPATH=PYTHONPATH + os.pathsep + os.environ.get("PYTHONPATH", ""))
EXE = Path(PYTHONPATH).parent / "apps" / "medspring"


def dest(name):
    return name.replace("-", "_")


def drift(decl, parser, runner_source, command=None):
    """Every difference between the declaration, the Python parser, the runner's use of the parsed
    switches and (when given) the `medspring study` options of `medspring help --json`."""
    problems = []
    actions = {a.option_strings[0][2:]: a for a in parser._actions if a.option_strings and a.dest != "help"}
    declared = {s["name"]: s for s in decl["switches"]}
    for name in sorted(set(actions) - set(declared)):
        problems.append(f"python parser: --{name} is not declared")
    for name, s in declared.items():
        if not re.search(rf"\ba\.{dest(name)}\b", runner_source):
            problems.append(f"__main__.py: declared --{name} is never read (a.{dest(name)})")
        a = actions.get(name)
        if a is None:
            problems.append(f"python parser: declared --{name} missing")
            continue
        if (a.help == argparse.SUPPRESS) != s["hidden"]:
            problems.append(f"python parser: --{name} hidden differs")
        if bool(a.required) != s["required"]:
            problems.append(f"python parser: --{name} required differs")
        if s["type"] == "flag" and a.nargs != 0:
            problems.append(f"python parser: --{name} takes a value but is declared a flag")
        if s["type"] == "choice" and list(a.choices or []) != s["value"].split("|"):
            problems.append(f"python parser: --{name} choices differ")
        numeric = s["type"] == "integer" and s["default"].lstrip("-").isdigit()
        if (numeric or s["type"] == "choice") and str(a.default) != s["default"]:
            problems.append(f"python parser: --{name} default {a.default} is not the declared {s['default']}")
    groups = {}
    for s in decl["switches"]:
        if s["group"]:
            groups.setdefault(s["group"], set()).add(s["name"])
    parsed_groups = [{a.option_strings[0][2:] for a in g._group_actions} for g in parser._mutually_exclusive_groups]
    if sorted(map(sorted, groups.values())) != sorted(map(sorted, parsed_groups)):
        problems.append(f"python parser: exclusive groups {parsed_groups} are not the declared {list(groups.values())}")
    if command is not None:
        shown = [(o["name"], o.get("value", ""), o.get("unit", ""), o.get("default", ""), o.get("help", ""))
                 for o in command["options"]]
        want = [(s["name"], s["value"], s["unit"], s["default"], s["help"]) for s in decl["switches"]
                if not s["hidden"]]
        for row in sorted(set(shown) ^ set(want)):
            side = "medspring study" if row in shown else "declared"
            problems.append(f"medspring study options differ ({side} only): --{row[0]}")
        if command.get("positional") != decl["positional"]:
            problems.append("medspring study: positional differs")
    return problems


def medspring_study_command():
    if not EXE.is_file():
        pytest.skip(f"{EXE} is not built")
    specs = json.loads(subprocess.run([str(EXE), "help", "--json"], check=True, capture_output=True,
                                      text=True).stdout)
    return next(c for c in specs["commands"] if c["name"] == "study")


def runner_source():
    return inspect.getsource(main_mod.main)


def test_both_command_lines_and_the_runner_are_the_declaration():
    decl = ms.study_runner_cli()
    names = [s["name"] for s in decl["switches"]]
    assert {"out", "scheduler", "workers", "resume", "yes", "quiet", "no-report", "scaling", "device",
            "set"} <= set(names)
    assert len(names) == len(set(names))
    assert drift(decl, main_mod.parser(), runner_source(), medspring_study_command()) == []


def test_drift_is_found():
    """The check fails on each kind of drift: a switch declared but not read by the runner, one added
    to the Python parser by hand, one missing from `medspring study`, a default changed on one side."""
    decl = ms.study_runner_cli()
    parser, source, command = main_mod.parser(), runner_source(), medspring_study_command()

    added = json.loads(json.dumps(decl))
    added["switches"].append(dict(added["switches"][3], name="frobnicate"))
    found = drift(added, parser, source)
    assert "__main__.py: declared --frobnicate is never read (a.frobnicate)" in found
    assert "python parser: declared --frobnicate missing" in found

    by_hand = main_mod.parser()
    by_hand.add_argument("--extra", action="store_true")
    assert drift(decl, by_hand, source) == ["python parser: --extra is not declared"]

    fewer = json.loads(json.dumps(command))
    fewer["options"] = [o for o in fewer["options"] if o["name"] != "scaling"]
    assert drift(decl, parser, source, fewer) == ["medspring study options differ (declared only): --scaling"]

    changed = json.loads(json.dumps(decl))
    next(s for s in changed["switches"] if s["name"] == "device")["default"] = "auto"
    assert drift(changed, parser, source) == ["python parser: --device default cpu is not the declared auto"]


def test_both_help_texts_list_every_declared_switch():
    decl = ms.study_runner_cli()
    py_help = subprocess.run([sys.executable, "-m", "medspring.study", "--help"], env=ENV, capture_output=True,
                             text=True, timeout=60)
    assert py_help.returncode == 0, py_help.stderr
    medspring_study_command()  # skips without the executable
    cpp_help = subprocess.run([str(EXE), "study", "--help"], capture_output=True, text=True, timeout=60)
    assert cpp_help.returncode == 0, cpp_help.stderr
    for s in decl["switches"]:
        for text in (py_help.stdout, cpp_help.stdout):
            assert (f"--{s['name']}" in text) != s["hidden"], (s["name"], text)


@pytest.mark.parametrize(
    "args, names",
    [
        (["s.json", "--out", "o", "--workers", "-1"], "--workers"),
        (["s.json", "--out", "o", "--scaling", "two"], "--scaling"),
        (["s.json", "--out", "o", "--workers", "2", "--scheduler", "tcp://h:1"], "--scheduler"),
        (["s.json", "--out", "o", "--device", "tpu"], "--device"),
        (["s.json"], "--out"),
    ],
)
def test_an_argument_mistake_is_one_line_naming_the_switch_and_exit_2(args, names, capsys):
    with pytest.raises(SystemExit) as e:
        main_mod.main(args)
    assert e.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("medspring study: ") and names in err[0], err
