"""Compare two ``results.json`` files figure by figure: are two runs the same run?

Used to show that a refactoring left the main job's results unchanged: every
number must agree to ``--tol`` (default 1e-9, absolute or relative) and every
other value exactly, except the measured times (keys naming a time or a
duration, and the run's wall clock), which differ from run to run.

    python benchmarks/compare_results.py BEFORE/results.json AFTER/results.json

Prints one line per difference and a summary; exits 1 when they differ.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys

#: Keys whose values are measured times (s), shares of them, or clock readings: not compared.  Settings that are
#: lengths of time (``window_s``) are compared.
TIME_KEY = re.compile(r"wall_time|clustering_s$|_times_s$|time_saving|elapsed|started|finished|^utc|_at$")


def is_time_key(key):
    """True for a key that holds a measured time or a clock reading."""
    return bool(TIME_KEY.search(str(key)))


def differences(before, after, tol, path="$"):
    """Every place where ``after`` differs from ``before``, as ``(path, before, after)``."""
    if isinstance(before, dict) and isinstance(after, dict):
        found = []
        for key in sorted(set(before) | set(after), key=str):
            if is_time_key(key):
                continue
            where = f"{path}.{key}"
            if key not in before or key not in after:
                found.append((where, before.get(key, "<absent>"), after.get(key, "<absent>")))
            else:
                found += differences(before[key], after[key], tol, where)
        return found
    if isinstance(before, list) and isinstance(after, list):
        if len(before) != len(after):
            return [(path, f"{len(before)} items", f"{len(after)} items")]
        return [
            d
            for i, (b, a) in enumerate(zip(before, after, strict=True))
            for d in differences(b, a, tol, f"{path}[{i}]")
        ]
    numbers = (int, float)
    if isinstance(before, numbers) and isinstance(after, numbers) and not isinstance(before, bool):
        if math.isnan(before) and math.isnan(after):
            return []
        if abs(before - after) <= tol * max(1.0, abs(before), abs(after)):
            return []
        return [(path, before, after)]
    return [] if before == after else [(path, before, after)]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--tol", type=float, default=1e-9)
    args = parser.parse_args(argv)
    with open(args.before) as handle:
        before = json.load(handle)
    with open(args.after) as handle:
        after = json.load(handle)
    found = differences(before, after, args.tol)
    for where, b, a in found[:50]:
        print(f"{where}: {b!r} -> {a!r}")
    print(f"{len(found)} difference(s) beyond {args.tol:g} (times excluded) between {args.before} and {args.after}")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
