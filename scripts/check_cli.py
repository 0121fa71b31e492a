#!/usr/bin/env python3
"""Keeps the command line's declarations (apps/commands.cpp) and everything else in step:

1. docs/cli.md is what `medspring help --markdown` prints (regenerate it when an option changes);
2. every option a command body reads (args.get/flag/number/integer/get_or, require_known lists in
   apps/cmd_*.cpp) is declared, a require_known list all for one command;
3. every `medspring COMMAND ... --option` written in README.md, CONTRIBUTING.md, docs/*.md and scripts/*.sh
   names an option declared for that command.

usage: check_cli.py MEDSPRING_EXE SOURCE_DIR     (exit 1 with one line per problem)
"""
import difflib
import json
import re
import subprocess
import sys
from pathlib import Path


def main(exe, root):
    root = Path(root)
    problems = []
    generated = subprocess.run([exe, "help", "--markdown"], check=True, capture_output=True, text=True).stdout
    committed = (root / "docs" / "cli.md").read_text()
    if generated != committed:
        diff = list(difflib.unified_diff(committed.splitlines(), generated.splitlines(), "docs/cli.md",
                                         "medspring help --markdown", lineterm="", n=0))
        problems.append("docs/cli.md differs from `medspring help --markdown` (regenerate: "
                        "build/apps/medspring help --markdown > docs/cli.md):\n  " + "\n  ".join(diff[:12]))

    specs = json.loads(subprocess.run([exe, "help", "--json"], check=True, capture_output=True, text=True).stdout)
    per_command = {}  # "run", "build", "build kidney" -> option names
    for c in specs["commands"]:
        per_command[c["name"]] = {o["name"] for o in c["options"]}
        for s in c["subcommands"]:
            per_command[c["name"] + " " + s["name"]] = {o["name"] for o in s["options"]}
            per_command[c["name"]] |= per_command[c["name"] + " " + s["name"]]
    everything = set().union(*per_command.values())

    for src in sorted((root / "apps").glob("cmd_*.cpp")):
        text = src.read_text()
        for m in re.finditer(r'args\.(?:get|flag|number|integer|get_or)\(\s*"([^"]+)"', text):
            if m.group(1) not in everything:
                line = text.count("\n", 0, m.start()) + 1
                problems.append(f"{src.relative_to(root)}:{line}: option --{m.group(1)} is read but declared "
                                "for no command in apps/commands.cpp")
        for m in re.finditer(r"require_known\(\s*\{([^}]*)\}", text):
            names = set(re.findall(r'"([^"]+)"', m.group(1)))
            if not any(names <= opts for opts in per_command.values()):
                line = text.count("\n", 0, m.start()) + 1
                best = max(per_command, key=lambda k: len(names & per_command[k]))
                problems.append(f"{src.relative_to(root)}:{line}: require_known lists "
                                f"{', '.join('--' + n for n in sorted(names - per_command[best]))}, not declared "
                                f"for `medspring {best}` in apps/commands.cpp")

    commands = {c["name"]: c for c in specs["commands"]}
    files = [root / "README.md", root / "CONTRIBUTING.md", *sorted((root / "docs").glob("*.md")),
             *sorted((root / "scripts").glob("*.sh"))]
    for f in files:
        if f.name == "cli.md":
            continue
        fenced = f.suffix == ".sh"
        for n, line in enumerate(f.read_text().splitlines(), 1):
            if f.suffix == ".md" and line.lstrip().startswith("```"):
                fenced = not fenced
                continue
            segments = [line.split(" #")[0]] if fenced else re.findall(r"`([^`]*)`", line)
            for seg in segments:
                for m in re.finditer(r"(?:^|[\s/\"'(])medspring\s+([a-z][\w-]*)((?:[^|;&]|&(?!&))*)", seg):
                    name, rest = m.group(1), m.group(2)
                    if name not in commands:
                        continue
                    rest = re.split(r"\bmedspring\s", rest)[0]
                    path = name
                    words = rest.split()
                    if commands[name]["subcommands"] and words and name + " " + words[0] in per_command:
                        path = name + " " + words[0]
                    for opt in re.findall(r"(?<![\w-])--([A-Za-z][\w-]*)", rest):
                        if opt != "help" and opt not in per_command[path]:
                            problems.append(f"{f.relative_to(root)}:{n}: `medspring {path} ... --{opt}`: "
                                            f"--{opt} is not an option of `medspring {path}`")
    for p in problems:
        print(p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
