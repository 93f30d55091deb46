#!/usr/bin/python3
"""Torque-tracking figure, after the paper's Fig. "torque-control-results".

Usage: /usr/bin/python3 tools/report/torque_tracking_figure.py RESULTS_DIR OUTPUT.png

Reads the time series phri::run_torque_tracking writes into RESULTS_DIR,
torque_tracking_<scenario>_<loop>.csv (t_s, error_norm_Nm, error_norm_true_Nm, ...), and draws
the norm of the joint torque tracking error ||tau_d - tau_s|| (as the torque sensors measure it)
over time, on a logarithmic axis: one panel per scenario (static on top, dynamic below), the
custom loop in blue and Kinova's high-velocity loop in orange, with a 50 ms moving average over
the raw 1 kHz samples. The legend gives RMS and 95th percentile over the statistics window, from
torque_tracking_summary.csv (the window starts after the switch transient, shaded). Headless (Agg
backend).
"""
import os
import sys

import numpy as np
from report_common import plt, read_rows, save_figure

SCENARIOS = ["static", "dynamic"]
LOOPS = [("custom", "custom torque loop", "tab:blue"),
         ("kinova_torque_high_velocity", "Kinova high-velocity torque loop", "tab:orange")]


def read_series(path):
    rows = read_rows(path)
    t = np.array([float(r["t_s"]) for r in rows])
    e = np.array([float(r["error_norm_Nm"]) for r in rows])
    return t, e


def moving_average(x, n):
    """Centred mean over n samples, over fewer at the ends (no edge dip)."""
    if x.size < n:
        return x
    kernel = np.ones(n)
    return np.convolve(x, kernel, mode="same") / np.convolve(np.ones_like(x), kernel, mode="same")


def read_summary(path):
    if not os.path.exists(path):
        return {}
    return {(r["scenario"], r["loop"]): r for r in read_rows(path)}


def main(argv):
    if len(argv) != 3:
        print(__doc__)
        return 2
    results, output = argv[1], argv[2]
    present = [s for s in SCENARIOS
               if any(os.path.exists(f"{results}/torque_tracking_{s}_{loop}.csv") for loop, _, _ in LOOPS)]
    if not present:
        print("no torque_tracking_*.csv in", results)
        return 1
    summary = read_summary(f"{results}/torque_tracking_summary.csv")
    fig, axes = plt.subplots(len(present), 1, figsize=(10, 3.6 * len(present)), squeeze=False)
    for ax, scenario in zip(axes[:, 0], present):
        for loop, label, color in LOOPS:
            path = f"{results}/torque_tracking_{scenario}_{loop}.csv"
            if not os.path.exists(path):
                continue
            t, e = read_series(path)
            stats = summary.get((scenario, loop))
            if stats is not None:
                text = f"RMS {float(stats['rms_Nm']):.3f}, p95 {float(stats['p95_Nm']):.3f} N.m"
                start = float(stats["window_start_s"])
            else:
                text = f"RMS {float(np.sqrt(np.mean(e ** 2))):.3f} N.m (whole series)"
                start = 0.0
            ax.semilogy(t, e, color=color, linewidth=0.4, alpha=0.35)
            ax.semilogy(t, moving_average(e, 50), color=color, linewidth=1.4, label=f"{label}: {text}")
            if start > 0.0:
                ax.axvspan(0.0, start, color="0.9", zorder=0)
        ax.set_title(f"{scenario} scenario", fontsize=10)
        ax.set_xlabel("time since the switch from position control [s]")
        ax.set_ylabel(r"$\|\tau_d - \tau_s\|$ [N.m]")
        ax.grid(which="both", alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    save_figure(fig, output, 130, "Joint torque tracking error (thin: 1 kHz samples, thick: 50 ms moving average)", 11,
                "torque tracking figure")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
