#!/usr/bin/env python3
"""Checks that every relative link in README.md, CONTRIBUTING.md and docs/**/*.md resolves to a file or
folder of the repository (CTest: docs_relative_links). Links inside code blocks are ignored; an inline
code span that names a page of docs/ (`docs/physics.md`, from the repository root) counts as a link, as
the README lists the docs that way. Web links (http, https, mailto) and pure anchors (#...) are not checked.

usage: check_links.py [REPO]   -> exit 0, or 1 with one line per broken link: file:line: target
"""

import re
import sys
from pathlib import Path

INLINE = re.compile(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+.*)?$")
CODE_MD = re.compile(r"`(docs/[\w./-]+\.md)`")
HTML = re.compile(r"""(?:src|href)=["']([^"']+)["']""")


def links(text):
    """(line number, target) of every link outside code."""
    fenced = False
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith(("```", "~~~")):
            fenced = not fenced
            continue
        if fenced:
            continue
        for m in CODE_MD.finditer(line):
            yield number, m.group(1)
        line = re.sub(r"`[^`]*`", "", line)  # inline code
        for pattern in (INLINE, HTML):
            for m in pattern.finditer(line):
                yield number, m.group(1)
        m = REFERENCE.match(line)
        if m:
            yield number, m.group(1)


def broken(repo: Path):
    files = [repo / "README.md", repo / "CONTRIBUTING.md", *sorted((repo / "docs").rglob("*.md"))]
    for f in files:
        if not f.is_file():
            continue
        for number, target in links(f.read_text(encoding="utf-8")):
            if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target) or target.startswith("#"):
                continue  # web link, mailto:, anchor
            path = target.split("#", 1)[0].split("?", 1)[0]
            if not path:
                continue
            resolved = (repo / path.lstrip("/")) if path.startswith("/") else (f.parent / path)
            if not resolved.exists() and not (path.startswith("docs/") and (repo / path).exists()):
                yield f"{f.relative_to(repo)}:{number}: {target}"


def main():
    repo = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[1]).resolve()
    bad = list(broken(repo))
    for line in bad:
        print(line)
    if bad:
        print(f"{len(bad)} broken relative link(s)", file=sys.stderr)
        return 1
    print("every relative link resolves")
    return 0


if __name__ == "__main__":
    sys.exit(main())
