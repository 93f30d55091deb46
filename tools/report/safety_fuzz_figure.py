#!/usr/bin/python3
"""Safety-fuzz figure.

Usage: /usr/bin/python3 tools/report/safety_fuzz_figure.py RESULTS_DIR OUTPUT.png

Reads RESULTS_DIR/safety_fuzz.csv (written by `phri experiment safety-fuzz`, one row per push or
fault window) and draws three panels: a compliance mode x low-level loop heat map of the
controller failures among the push windows (each cell: failures / pushes), the same for the
sensor-fault windows, and a scatter of the push's peak force against the peak speed ratio
max |qd| / velocity limit (green: no violation, orange: operator-possible violation, red:
controller failure; the dashed line is the overspeed threshold 1.05). Headless (Agg backend).
"""
import os
import sys

import numpy as np
from report_common import plt, read_rows, save_figure

MODES = ["stiff", "null_space", "full_body", "dual"]
LOOPS = ["position", "kinova_torque", "kinova_torque_high_velocity", "custom"]
LOOP_LABELS = ["position", "kinova\ntorque", "kinova torque\nhigh velocity", "custom"]
PUSH_KINDS = {"push", "limit_push", "wrist_fold"}


def heat_map(ax, rows, title):
    failures = np.zeros((len(MODES), len(LOOPS)))
    totals = np.zeros((len(MODES), len(LOOPS)))
    for r in rows:
        if r["mode"] not in MODES or r["loop"] not in LOOPS:
            continue
        i, j = MODES.index(r["mode"]), LOOPS.index(r["loop"])
        totals[i, j] += 1
        failures[i, j] += r["controller_failure"] == "1"
    share = np.divide(failures, totals, out=np.zeros_like(failures), where=totals > 0)
    image = ax.imshow(share, cmap="Reds", vmin=0.0, vmax=max(share.max(), 1e-9))
    for i in range(len(MODES)):
        for j in range(len(LOOPS)):
            text = "-" if totals[i, j] == 0 else f"{int(failures[i, j])}/{int(totals[i, j])}"
            ax.text(j, i, text, ha="center", va="center", fontsize=9,
                    color="white" if share[i, j] > 0.6 * share.max() > 0 else "black")
    ax.set_xticks(range(len(LOOPS)), LOOP_LABELS, fontsize=8)
    ax.set_yticks(range(len(MODES)), MODES)
    ax.set_title(title)
    plt.colorbar(image, ax=ax, fraction=0.046, pad=0.04, label="share of windows")


def scatter(ax, rows):
    groups = [("no violation", "tab:green", lambda r: r["violations"] == ""),
              ("operator-possible", "tab:orange", lambda r: r["violations"] != "" and r["operator_possible"] == "1"),
              ("controller failure", "tab:red", lambda r: r["controller_failure"] == "1")]
    for label, color, keep in groups:
        chosen = [r for r in rows if keep(r)]
        if not chosen:
            continue
        force = [float(r["force_N"]) for r in chosen]
        ratio = [float(r["max_speed_ratio"]) for r in chosen]
        ax.scatter(force, ratio, s=10, alpha=0.6, color=color, label=f"{label} ({len(chosen)})")
    ax.axhline(1.05, color="black", linestyle="--", linewidth=1, label="overspeed threshold")
    ax.set_xlabel("peak push force [N]")
    ax.set_ylabel("max |qd| / velocity limit")
    ax.set_title("Pushes: force vs peak speed ratio")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)


def main(argv):
    if len(argv) != 3:
        print(__doc__)
        return 2
    results, output = argv[1], argv[2]
    path = os.path.join(results, "safety_fuzz.csv")
    if not os.path.exists(path):
        print("no safety_fuzz.csv in", results)
        return 1
    rows = read_rows(path)
    pushes = [r for r in rows if r["kind"] in PUSH_KINDS]
    faults = [r for r in rows if r["kind"] == "fault"]
    fig, axes = plt.subplots(1, 3, figsize=(19, 5.5))
    heat_map(axes[0], pushes, "Controller failures: pushes")
    heat_map(axes[1], faults, "Controller failures: sensor faults")
    scatter(axes[2], pushes)
    failures = sum(r["controller_failure"] == "1" for r in rows)
    save_figure(fig, output, 110, title=f"Safety fuzz: {len(pushes)} pushes, {len(faults)} faults, "
                f"{failures} controller failures", label="figure")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
