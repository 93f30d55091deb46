#!/usr/bin/python3
"""Static torque tracking against the plant's drive-gain error.

Usage: /usr/bin/python3 tools/report/static_sweep_figure.py RESULTS_DIR OUTPUT.png

Reads RESULTS_DIR/static_sweep.csv (phri::run_static_sweep: one row per drive-gain error and
mismatch seed) and draws, against the error bound f (each joint's K_T G_r off by up to +-f):
left, the RMS of ||tau_d - tau_s|| of both loops (dots: seeds, line: median; log axis);
right, the high-velocity / custom ratio (dots and median) with the paper's 10x line.
Headless (Agg backend).
"""
import os
import sys

import numpy as np
from report_common import finish_axes, plt, read_rows, save_figure


def main():
    if len(sys.argv) != 3:
        print(__doc__)
        return 2
    path = os.path.join(sys.argv[1], "static_sweep.csv")
    rows = read_rows(path)
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
    finish_axes(ax1, "drive gain error bound f [%] (K_T G_r off by up to +-f)", "RMS of ||tau_d - tau_s|| [N.m]",
                "static scenario: torque tracking error", log_y=True, fontsize=8)

    ax2.scatter(err, ratio, s=14, color="k", alpha=0.5, label="one mismatch seed")
    ax2.plot(levels, medians(ratio), "-o", color="k", label="median")
    ax2.axhline(10.0, color="tab:red", ls="--", label="paper's target 10x")
    finish_axes(ax2, "drive gain error bound f [%]", "RMS high-velocity / RMS custom", "static scenario: ratio",
                log_y=True, fontsize=8)
    save_figure(fig, sys.argv[2], 120)
    return 0


if __name__ == "__main__":
    sys.exit(main())
