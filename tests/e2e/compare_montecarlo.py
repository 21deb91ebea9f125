#!/usr/bin/env python3
"""Compares two `sdins montecarlo` output directories: every stats_*.csv byte for byte and
summary.json with its "timing" object (wall clocks, ranks, threads) removed. Exit 0 if identical."""
import json
import pathlib
import sys


def main() -> int:
    a, b = (pathlib.Path(p) for p in sys.argv[1:3])
    csv_a = sorted(p.name for p in a.glob("stats_*.csv"))
    csv_b = sorted(p.name for p in b.glob("stats_*.csv"))
    if not csv_a or csv_a != csv_b:
        print(f"different CSV sets: {a}: {csv_a}, {b}: {csv_b}")
        return 1
    for name in csv_a:
        if (a / name).read_bytes() != (b / name).read_bytes():
            print(f"{name} differs between {a} and {b}")
            return 1
    ja = json.loads((a / "summary.json").read_text())
    jb = json.loads((b / "summary.json").read_text())
    ja.pop("timing", None)
    jb.pop("timing", None)
    # Python floats round-trip the JSON numbers exactly, so == is a bitwise comparison.
    if json.dumps(ja, sort_keys=True) != json.dumps(jb, sort_keys=True):
        print(f"summary.json (without timing) differs between {a} and {b}")
        return 1
    print(f"identical: {b} == {a} ({', '.join(csv_a)}, summary.json without timing)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
