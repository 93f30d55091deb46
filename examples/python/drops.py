#!/usr/bin/env python3
"""The paper's drop test from Python: a 1.25 kg mass hangs on a slack 25 cm cable under the tool and is
released; the cable jerks taut and the controller holds the end effector against the shock. A few drops,
each with another low-level loop (or compliance mode), stepped one period at a time from Python, then
plotted with matplotlib.

    /usr/bin/python3 examples/python/drops.py [--out drops.png] [--seconds 3] [--release 1] [--show]

phri must be importable: from a build tree, PYTHONPATH=build/release/python (the script also looks
there itself); once installed (cmake --install), nothing to set.
"""
import argparse
import pathlib
import sys
from typing import Dict

import numpy as np
import numpy.typing as npt

try:
    import phri
except ImportError:  # run from the source tree before installing: use the release build
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "build/release/python"))
    import phri

POSTURE = [0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57]  # the paper demo's posture: arm half extended

# (label, compliance mode, low-level loop)
DROPS = [
    ("stiff, custom loop", phri.ComplianceMode.stiff, phri.LowLevelMode.custom),
    ("stiff, Kinova high-velocity loop", phri.ComplianceMode.stiff, phri.LowLevelMode.kinova_torque_high_velocity),
    ("null-space compliance, custom loop", phri.ComplianceMode.null_space, phri.LowLevelMode.custom),
]


Series = Dict[str, npt.NDArray[np.float64]]


def drop(mode: phri.ComplianceMode, loop_mode: phri.LowLevelMode, seconds: float, release_s: float) -> Series:
    """One drop; returns per-cycle arrays: time, tool height change, cable force, end-effector error."""
    config = phri.SimRobotConfig.from_yaml_file(phri.locate("configs/plant_gen3.yaml"))
    config.initial_q_rad = POSTURE
    config.drop_test.enabled = True
    config.drop_test.release_time_s = release_s
    robot = phri.SimRobot(config)
    settings = phri.ControllerSettings()
    settings.initial_compliance = mode
    settings.initial_loop = loop_mode
    controller = phri.Controller(settings)
    loop = phri.ClosedLoop(robot, controller)
    truth = robot.truth()  # views of the plant's truth, updated by every period
    z0 = truth.sensor_position_m[2]
    n = round(seconds / robot.period_s)
    t, dz, cable, error = (np.empty(n) for _ in range(4))
    for k in range(n):
        loop.step()  # read, controller step, write: one period
        t[k] = truth.time_s
        dz[k] = 1e3 * (truth.sensor_position_m[2] - z0)
        cable[k] = truth.cable_force_N
        error[k] = 1e3 * np.linalg.norm(controller.ee_error[:3])
    return {"t": t, "dz_mm": dz, "cable_N": cable, "ee_error_mm": error}


def plot(results: Dict[str, Series], release_s: float, out: str, show: bool) -> None:
    import matplotlib
    if not show:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 8))
    for label, r in results.items():
        axes[0].plot(r["t"], r["cable_N"], label=label)
        axes[1].plot(r["t"], r["dz_mm"], label=label)
        axes[2].plot(r["t"], r["ee_error_mm"], label=label)
    for axis, name in zip(axes, ("cable force [N]", "tool height change [mm]", "end-effector error [mm]")):
        axis.axvline(release_s, color="grey", linestyle=":", linewidth=1)
        axis.set_ylabel(name)
        axis.grid(True, alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title("Drop test: 1.25 kg on a 25 cm cable, released under the tool")
    axes[2].set_xlabel("time [s]")
    figure.tight_layout()
    figure.savefig(out, dpi=110)
    if show:
        plt.show()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="drops.png", help="figure file (default: drops.png)")
    parser.add_argument("--seconds", type=float, default=3.0, help="simulated time of each drop (default: 3)")
    parser.add_argument("--release", type=float, default=1.0, help="release time (default: 1 s)")
    parser.add_argument("--show", action="store_true", help="also open a window")
    args = parser.parse_args()
    results = {}
    print(f"| drop | peak cable force N | tool sag mm | max EE error mm | EE error at end mm |")
    print("|---|---|---|---|---|")
    for label, mode, loop_mode in DROPS:
        r = drop(mode, loop_mode, args.seconds, args.release)
        results[label] = r
        after = r["t"] >= args.release
        print(f"| {label} | {r['cable_N'].max():.1f} | {-r['dz_mm'][after].min():.2f} | "
              f"{r['ee_error_mm'][after].max():.2f} | {r['ee_error_mm'][-1]:.2f} |")
    plot(results, args.release, args.out, args.show)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
