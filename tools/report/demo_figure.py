#!/usr/bin/python3
"""Figure of a `phri run` log: end-effector error, F/T wrench norm with the dual-compliance
thresholds and the touched intervals shaded, desired joint torques, and the modes.

usage: tools/report/demo_figure.py LOG.csv OUT.png [--touch 8 --release 4]
"""
import argparse
import sys

import numpy as np
from report_common import plt, save_figure


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("log")
    parser.add_argument("out")
    parser.add_argument("--touch", type=float, default=8.0)
    parser.add_argument("--release", type=float, default=4.0)
    args = parser.parse_args()
    # atleast_1d: a one-row log (a run stopped in its first cycle) reads as a 0-d array.
    data = np.atleast_1d(np.genfromtxt(args.log, delimiter=",", names=True))
    t = data["time_s"]
    tau_d = np.column_stack([data[n] for n in data.dtype.names if n.startswith("tau_d_")])

    fig, axes = plt.subplots(4, 1, figsize=(12, 11), sharex=True,
                             gridspec_kw={"height_ratios": [2, 2, 2, 1]})
    touched = data["touched"] > 0.5
    for ax in axes[:3]:
        # Shade the dual-compliance "touched" intervals.
        spans, inside, start = [], False, None
        for k in range(len(t)):
            if touched[k] and not inside:
                inside, start = True, t[k]
            elif not touched[k] and inside:
                inside = False
                spans.append((start, t[k]))
        if inside:
            spans.append((start, t[-1]))
        for a, b in spans:
            ax.axvspan(a, b, color="0.85", zorder=0)

    axes[0].plot(t, 1e3 * data["err_pos_m"], label="position error [mm]")
    axes[0].plot(t, np.degrees(data["err_ori_rad"]), label="orientation error [deg]")
    axes[0].set_ylabel("end-effector error")
    axes[0].set_yscale("symlog", linthresh=0.1)
    axes[0].legend(loc="upper right")
    axes[0].grid(True, alpha=0.3)

    axes[1].plot(t, data["wrench_norm"], color="k", lw=0.8, label="F/T wrench norm")
    axes[1].axhline(args.touch, color="tab:blue", ls="--", label=f"touch threshold {args.touch:g}")
    axes[1].axhline(args.release, color="tab:orange", ls="--", label=f"release threshold {args.release:g}")
    axes[1].set_ylabel("wrench norm [N, N.m]")
    axes[1].legend(loc="upper right")
    axes[1].grid(True, alpha=0.3)

    for j in range(tau_d.shape[1]):
        axes[2].plot(t, tau_d[:, j], lw=0.8, label=f"joint {j + 1}")
    axes[2].set_ylabel(r"desired torque $\tau_d$ [N.m]")
    axes[2].legend(loc="upper right", ncol=7, fontsize=8)
    axes[2].grid(True, alpha=0.3)

    axes[3].step(t, data["compliance_mode"], where="post", label="compliance (0 stiff, 1 null-space, 2 full-body, 3 dual)")
    axes[3].step(t, data["low_level_loop"] + 0.05, where="post", label="low level (0 position, 1 K torque, 2 K HV, 3 custom)")
    axes[3].set_ylabel("mode")
    axes[3].set_xlabel("time [s]")
    axes[3].legend(loc="upper left", fontsize=8)
    axes[3].grid(True, alpha=0.3)
    save_figure(fig, args.out, 110, "phri demo on the simulated Kinova Gen3 (shaded: dual compliance, end effector touched)")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    sys.exit(main())
