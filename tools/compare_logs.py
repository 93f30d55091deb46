#!/usr/bin/env python3
"""Compares two phri run logs (CSV) cell by cell, the wall-clock columns (cycle_time_s) left out:
a refactor that keeps the behaviour prints `0 cells differ` (the physics and the controller are
deterministic for a given seed). Exit status 1 when anything differs.

    tools/compare_logs.py before/phri_demo.csv after/phri_demo.csv
"""
import csv
import sys

WALL_CLOCK = {"cycle_time_s"}


def main(argv):
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[-1].strip(), file=sys.stderr)
        return 2
    with open(argv[1], newline="") as a_file, open(argv[2], newline="") as b_file:
        a_rows, b_rows = csv.reader(a_file), csv.reader(b_file)
        a_head, b_head = next(a_rows), next(b_rows)
        if a_head != b_head:
            print(f"the columns differ: {len(a_head)} vs {len(b_head)}")
            return 1
        compared = [i for i, name in enumerate(a_head) if name not in WALL_CLOCK]
        rows = differ = 0
        first = None
        for a, b in zip(a_rows, b_rows):
            rows += 1
            for i in compared:
                if a[i] != b[i]:
                    differ += 1
                    first = first or (rows, a_head[i], a[i], b[i])
        extra = sum(1 for _ in a_rows) + sum(1 for _ in b_rows)
    print(f"{rows} rows, {len(compared)} columns compared: {differ} cells differ" +
          (f"; first at row {first[0]}, {first[1]}: {first[2]} vs {first[3]}" if first else "") +
          (f"; {extra} rows in one log only" if extra else ""))
    return 1 if differ or extra else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
