#!/usr/bin/env python3
"""Writes the seed of CTest's cost data (tests/ctest-costs/*.txt) from a build tree's measured costs.

CTest runs the tests of a parallel run in descending order of cost; a fresh build tree (CI's) has none, so it
runs them in declaration order and a long test declared late (the WebAssembly build, the thin-tetrahedron runs
under the sanitizers) starts last and runs alone on one core at the end. scripts/test.sh and scripts/sanitize.sh
copy the seed into a fresh tree's Testing/Temporary/CTestCostData.txt. Only the order changes, never what runs.

    /usr/bin/python3 scripts/ctest_costs.py build > tests/ctest-costs/plain.txt
    /usr/bin/python3 scripts/ctest_costs.py build-asan > tests/ctest-costs/sanitize.txt
"""
import pathlib
import sys

MIN_SECONDS = 2.0  # shorter tests keep their declaration order (cost 0)


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    path = pathlib.Path(sys.argv[1]) / "Testing" / "Temporary" / "CTestCostData.txt"
    if not path.is_file():
        print(f"ctest_costs.py: {path}: no cost data (run ctest in that tree first)", file=sys.stderr)
        return 1
    rows = []
    for line in path.read_text().splitlines():
        if line == "---":
            break  # the failed tests of the last run follow: not part of the seed
        parts = line.split()
        if len(parts) == 3 and float(parts[2]) >= MIN_SECONDS:
            rows.append((float(parts[2]), parts[0]))
    for cost, name in sorted(rows, reverse=True):
        print(f"{name} 1 {cost:.1f}")
    print("---")
    return 0


if __name__ == "__main__":
    sys.exit(main())
