#!/usr/bin/env python3
"""Compare two metrics.json files (refract compare / the default job) field by field.

Usage: scripts/compare-metrics.py BEFORE/metrics.json AFTER/metrics.json

Every record is matched by (scene, method, backend, params); every field but the timings
(`ms_per_frame`) must be identical: the same rows in the same order, the same numbers to the
last bit (the CPU backend and the reference are deterministic; the GPU backend is on the same
driver). Exits 1 and lists the differences otherwise. Used to show that a refactoring changed
no result (the architecture issue's "behaviour unchanged").
"""

import json
import sys

TIMING_FIELDS = {"ms_per_frame"}


def key(record):
    return (record["scene"], record["method"], record["backend"], record["params"])


def main():
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    with open(sys.argv[1]) as f:
        before = json.load(f)
    with open(sys.argv[2]) as f:
        after = json.load(f)
    problems = []
    if [key(r) for r in before] != [key(r) for r in after]:
        problems.append(
            f"rows differ: {len(before)} before, {len(after)} after; "
            f"only before: {sorted(set(map(key, before)) - set(map(key, after)))}; "
            f"only after: {sorted(set(map(key, after)) - set(map(key, before)))}"
        )
    compared = 0
    for b, a in zip(before, after):
        fields = (set(b) | set(a)) - TIMING_FIELDS
        for field in sorted(fields):
            compared += 1
            if b.get(field) != a.get(field):
                problems.append(f"{key(b)} {field}: {b.get(field)!r} -> {a.get(field)!r}")
    if problems:
        print(f"{len(problems)} differences:")
        for p in problems[:50]:
            print("  " + p)
        return 1
    print(f"identical: {len(before)} records, {compared} values (timings excluded)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
