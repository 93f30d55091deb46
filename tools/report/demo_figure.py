#!/usr/bin/python3
"""Figure of a `phri run` log: end-effector error, F/T wrench norm with the dual-compliance
thresholds and the touched intervals shaded, desired joint torques, and the modes.

usage: tools/report/demo_figure.py LOG.csv OUT.png [--touch 8 --release 4] [--arm NAME] [--no-ft]

--arm names the arm in the title (its robot bundle's name); --no-ft: the arm has no F/T sensor,
so the wrench panel (always empty then) is left out.
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
    parser.add_argument("--arm", default="arm")
    parser.add_argument("--no-ft", action="store_true")
    args = parser.parse_args()
    # atleast_1d: a one-row log (a run stopped in its first cycle) reads as a 0-d array.
    data = np.atleast_1d(np.genfromtxt(args.log, delimiter=",", names=True))
    t = data["time_s"]
    tau_d = np.column_stack([data[n] for n in data.dtype.names if n.startswith("tau_d_")])

    panels = 3 if args.no_ft else 4
    fig, axes = plt.subplots(panels, 1, figsize=(12, 11 if panels == 4 else 8.5), sharex=True,
                             gridspec_kw={"height_ratios": [2, 2, 2, 1] if panels == 4 else [2, 2, 1]})
    ee_ax = axes[0]
    wrench_ax = None if args.no_ft else axes[1]
    tau_ax, mode_ax = axes[-2], axes[-1]
    touched = data["touched"] > 0.5
    for ax in axes[:-1]:
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

    ee_ax.plot(t, 1e3 * data["err_pos_m"], label="position error [mm]")
    ee_ax.plot(t, np.degrees(data["err_ori_rad"]), label="orientation error [deg]")
    ee_ax.set_ylabel("end-effector error")
    ee_ax.set_yscale("symlog", linthresh=0.1)
    ee_ax.legend(loc="upper right")
    ee_ax.grid(True, alpha=0.3)

    if wrench_ax is not None:
        wrench_ax.plot(t, data["wrench_norm"], color="k", lw=0.8, label="F/T wrench norm")
        wrench_ax.axhline(args.touch, color="tab:blue", ls="--", label=f"touch threshold {args.touch:g}")
        wrench_ax.axhline(args.release, color="tab:orange", ls="--", label=f"release threshold {args.release:g}")
        wrench_ax.set_ylabel("wrench norm [N, N.m]")
        wrench_ax.legend(loc="upper right")
        wrench_ax.grid(True, alpha=0.3)

    for j in range(tau_d.shape[1]):
        tau_ax.plot(t, tau_d[:, j], lw=0.8, label=f"joint {j + 1}")
    tau_ax.set_ylabel(r"desired torque $\tau_d$ [N.m]")
    tau_ax.legend(loc="upper right", ncol=7, fontsize=8)
    tau_ax.grid(True, alpha=0.3)

    mode_ax.step(t, data["compliance_mode"], where="post", label="compliance (0 stiff, 1 null-space, 2 full-body, 3 dual)")
    mode_ax.step(t, data["low_level_loop"] + 0.05, where="post",
                 label="low level (0 position, 1 K torque, 2 K HV, 3 custom, 4 torque)")
    mode_ax.set_ylabel("mode")
    mode_ax.set_xlabel("time [s]")
    mode_ax.legend(loc="upper left", fontsize=8)
    mode_ax.grid(True, alpha=0.3)
    save_figure(fig, args.out, 110, f"phri demo on the simulated {args.arm} (shaded: dual compliance, end effector touched)")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    sys.exit(main())
