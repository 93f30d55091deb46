#!/usr/bin/python3
"""Static torque tracking against the plant's drive-gain error.

Usage: /usr/bin/python3 tools/report/static_sweep_figure.py RESULTS_DIR OUTPUT.png

Reads RESULTS_DIR/static_sweep.csv (phri::run_static_sweep: one row per drive-gain error and
mismatch seed) and draws, against the error bound f (each joint's K_T G_r off by up to +-f):
left, the RMS of ||tau_d - tau_s|| of both loops (dots: seeds, line: median; log axis);
right, the high-velocity / custom ratio (dots and median) with the paper's 10x line.
Headless (Agg backend).
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    if len(sys.argv) != 3:
        print(__doc__)
        return 2
    path = os.path.join(sys.argv[1], "static_sweep.csv")
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        print("static_sweep_figure: no rows in " + path)
        return 1
    err = np.array([100.0 * float(r["torque_constant_error"]) for r in rows])
    custom = np.array([float(r["custom_rms_Nm"]) for r in rows])
    hv = np.array([float(r["high_velocity_rms_Nm"]) for r in rows])
    ratio = np.array([float(r["ratio"]) for r in rows])
    levels = np.unique(err)

    def medians(values):
        return np.array([np.median(values[err == e]) for e in levels])

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for values, label, color in ((custom, "custom torque loop", "tab:blue"),
                                 (hv, "Kinova high-velocity loop", "tab:orange")):
        ax1.scatter(err, values, s=14, color=color, alpha=0.5)
        ax1.plot(levels, medians(values), "-o", color=color, label=label + " (median)")
    ax1.set_yscale("log")
    ax1.set_xlabel("drive gain error bound f [%] (K_T G_r off by up to +-f)")
    ax1.set_ylabel("RMS of ||tau_d - tau_s|| [N.m]")
    ax1.set_title("static scenario: torque tracking error")
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=8)

    ax2.scatter(err, ratio, s=14, color="k", alpha=0.5, label="one mismatch seed")
    ax2.plot(levels, medians(ratio), "-o", color="k", label="median")
    ax2.axhline(10.0, color="tab:red", ls="--", label="paper's target 10x")
    ax2.set_yscale("log")
    ax2.set_xlabel("drive gain error bound f [%]")
    ax2.set_ylabel("RMS high-velocity / RMS custom")
    ax2.set_title("static scenario: ratio")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=120)
    return 0


if __name__ == "__main__":
    sys.exit(main())
