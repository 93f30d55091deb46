#!/usr/bin/python3
"""A shipped third-party arm end to end (robots/<arm>: its maker's URDF data and limits, a generic
drive, no F/T sensor): `phri run` on its demo-like configuration, then its log read back.

  third_party_arm.py --phri PHRI --config configs/<arm>.yaml --out DIR

Checks: the run completed with nothing held, degraded or refused; dual compliance's trigger read the
observer's wrench estimate (the start-up line says so) and fired during dual compliance (the log's
`touched` column rises while `compliance_mode` is dual) although the arm has no F/T sensor.
"""
import argparse
import csv
import glob
import os
import re
import subprocess
import sys

DUAL = 3  # compliance_mode's code for dual compliance (the log's legend)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--phri", required=True)
    ap.add_argument("--config", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    run = subprocess.run([a.phri, "run", "--config", a.config, "--lockstep", "--out", a.out, "--no-figure", "--log", "csv"],
                         capture_output=True, text=True, cwd=a.out, timeout=300)
    text = run.stdout + run.stderr
    failures = 0

    def check(ok, what):
        nonlocal failures
        print(("PASS " if ok else "FAIL ") + what)
        failures += 0 if ok else 1

    check(run.returncode == 0, f"phri run exited with {run.returncode}")
    check("touch trigger: end-effector wrench estimated from the observer" in text,
          "the touch trigger reads the observer's wrench estimate (no F/T sensor)")
    summary = re.search(r"(\d+) cycles, .*?(\d+) held cycles; (\d+) degraded spells; (\d+) refused writes", text)
    check(summary is not None and summary.group(2) == summary.group(3) == summary.group(4) == "0",
          "nothing held, degraded or refused: " + (summary.group(0) if summary else "no summary line"))
    logs = glob.glob(os.path.join(a.out, "*.csv"))
    check(len(logs) == 1, f"one CSV log in {a.out}")
    if len(logs) == 1:
        touches, touched_rows, previous = 0, 0, 0
        with open(logs[0]) as f:
            for row in csv.DictReader(f):
                touched = int(row["touched"])
                if touched and int(row["compliance_mode"]) == DUAL:
                    touched_rows += 1
                    touches += 1 if not previous else 0
                previous = touched
        check(touches >= 1, f"dual compliance's trigger fired: {touches} touch(es), {touched_rows} cycles touched")
    if failures:
        print(text[-4000:])
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
