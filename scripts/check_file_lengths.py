#!/usr/bin/env python3
"""Fails when a hand-written source file is longer than the limit (issue 22: files a newcomer can read
in one sitting; CTest: source_file_lengths). Source files are C++, CUDA, JavaScript and Python
(.cpp .cc .hpp .h .cu .cuh .js .mjs .py) tracked by git (without git: the tree, skipping build
folders). Generated and third-party files are not checked: build outputs (build*/, web/dist/),
web/node_modules/ and any folder named third_party/ or vendor/. A file over the limit is listed with its
length; split it along its own seams (docs/architecture.md) rather than raising the limit.

usage: check_file_lengths.py [REPO] [--limit N]   (default 650 lines)
  -> exit 0 with the longest file named, or 1 with one line per file over the limit: path: N lines
"""

import argparse
import os
import subprocess
import sys
from pathlib import Path

EXTENSIONS = {".cpp", ".cc", ".hpp", ".h", ".cu", ".cuh", ".js", ".mjs", ".py"}
# Generated or third-party: path prefixes (relative, '/'-separated) and folder names anywhere.
EXCLUDED_PREFIXES = ("web/dist/", "web/node_modules/")
EXCLUDED_FOLDERS = {"node_modules", "third_party", "vendor", ".git", "__pycache__", ".cache"}


def excluded(rel):
    parts = rel.split("/")
    if rel.startswith(EXCLUDED_PREFIXES) or parts[0].startswith(("build", "out")):
        return True
    return any(p in EXCLUDED_FOLDERS for p in parts[:-1])


def source_files(repo):
    """Relative paths of the source files: git's list where the repository is a checkout, else a walk."""
    try:
        out = subprocess.run(["git", "-C", str(repo), "ls-files", "-z"], capture_output=True, check=True)
        paths = [p for p in out.stdout.decode("utf-8", "replace").split("\0") if p]
    except (OSError, subprocess.CalledProcessError):
        paths = []
        for root, dirs, files in os.walk(repo):
            dirs[:] = [d for d in dirs if d not in EXCLUDED_FOLDERS]
            for name in files:
                paths.append(Path(root, name).relative_to(repo).as_posix())
    return sorted(p for p in paths if Path(p).suffix in EXTENSIONS and not excluded(p))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("repo", nargs="?", default=Path(__file__).resolve().parent.parent, type=Path)
    ap.add_argument("--limit", type=int, default=650, help="most lines a file may have (default 650)")
    args = ap.parse_args()
    lengths = []
    for rel in source_files(args.repo):
        path = args.repo / rel
        if not path.is_file():  # listed by git but deleted in the work tree
            continue
        with open(path, "rb") as f:
            lengths.append((sum(1 for _ in f), rel))
    if not lengths:
        print(f"check_file_lengths: no source files under {args.repo}", file=sys.stderr)
        return 1
    lengths.sort(key=lambda t: (-t[0], t[1]))
    long = [(n, rel) for n, rel in lengths if n > args.limit]
    for n, rel in long:
        print(f"{rel}: {n} lines (limit {args.limit}): split it along its seams")
    if long:
        print(f"check_file_lengths: {len(long)} of {len(lengths)} source files over {args.limit} lines")
        return 1
    n, rel = lengths[0]
    print(f"check_file_lengths: {len(lengths)} source files, all <= {args.limit} lines (longest {rel}: {n})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
