"""ctest `evaluate_quick`: runs `phri evaluate --quick` (argument vector, no shell) and checks the report:
the five sections and their figures exist, report.html is self-contained (figures inline), every
number in the tables is finite, and the protocol table states what ran: every row has a source, and the
drop test's drops per mode equals the drops its runs file holds.

Usage: check_report.py PHRI_EXECUTABLE OUTPUT_DIR
"""
import csv
import math
import re
import subprocess
import sys


def main(argv):
    phri, out = argv[1], argv[2]
    run = subprocess.run([phri, "evaluate", "--quick", "--out", out], capture_output=True, text=True, timeout=900)
    print(run.stdout[-4000:])
    if run.returncode != 0:
        print(run.stderr)
        print(f"phri evaluate --quick exited with {run.returncode}")
        return 1
    with open(f"{out}/report.md") as f:
        md = f.read()
    with open(f"{out}/report.html") as f:
        page = f.read()
    failures = []
    for section in ("## 1. Friction identification", "## 2. Torque tracking", "## 3. Drop test",
                    "## 4. Dynamic trajectory tracking", "## 5. Dual compliance"):
        if section not in md:
            failures.append(f"missing section {section!r}")
    figures = page.count('src="data:image/png;base64,')
    if figures < 5:
        failures.append(f"{figures} inline figures in report.html, expected at least 5")
    if re.search(r'<img src="(?!data:)', page):
        failures.append("report.html links an external image")
    for line in md.splitlines():
        if not line.startswith("|"):
            continue
        for cell in line.strip("|").split("|"):
            for token in re.findall(r"[-+]?(?:\d+\.?\d*(?:e[-+]?\d+)?|nan|inf)", cell.strip().lower()):
                if token in ("nan", "inf") or not math.isfinite(float(token)):
                    failures.append(f"non-finite number in table row: {line}")
    failures += protocol_failures(out, md)
    for f in failures:
        print("FAIL:", f)
    print(f"report checked: {len(failures)} failures, {figures} inline figures")
    return 1 if failures else 0


def protocol_failures(out, md):
    with open(f"{out}/protocol.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    failures = [f"protocol row without a source: {r}" for r in rows if not r["source"].strip()]
    for name in ("friction identification", "torque tracking", "drop test", "dynamic tracking", "dual compliance"):
        if not any(r["experiment"] == name for r in rows):
            failures.append(f"protocol table has no row of {name!r}")
    with open(f"{out}/drop_test/drop_test_runs.csv", newline="") as f:
        runs = list(csv.DictReader(f))
    drops = next((r["value"] for r in rows if r["experiment"] == "drop test" and r["parameter"] == "drops per mode"), None)
    torque_runs = sum(1 for r in runs if r["mode"] == "torque")
    if drops != str(torque_runs):
        failures.append(f"protocol table says {drops} drops per mode, the runs file holds {torque_runs} torque drops")
    if "The protocol of each evaluation as this run used it" not in md:
        failures.append("report.md lacks the protocol table")
    return failures


if __name__ == "__main__":
    sys.exit(main(sys.argv))
