#!/usr/bin/python3
"""ISO 9283 figure: accuracy (AP) and repeatability (RP) per pose and loop, and each arrival's error.

Usage: /usr/bin/python3 tools/report/iso9283_figure.py RESULTS_DIR OUTPUT.png

Reads what phri::run_iso9283 writes into RESULTS_DIR:
  iso9283_poses.csv     loop, valid, pose, ap_mm, rp_mm, ... (one row per loop and pose)
  iso9283_arrivals.csv  loop, valid, pose, dx_mm, dy_mm, dz_mm, ... (one row per arrival)
Left: AP and RP per pose, a bar per loop (hatched: a run that is not valid). Right: every
arrival's position error (x-y plane of the world, mm), one colour per loop. Headless (Agg backend).
"""
import sys

import numpy as np
from report_common import plt, read_rows, save_figure


def main(argv):
    if len(argv) != 3:
        print(__doc__)
        return 2
    results, output = argv[1], argv[2]
    poses = read_rows(f"{results}/iso9283_poses.csv")
    arrivals = read_rows(f"{results}/iso9283_arrivals.csv")
    if not poses:
        print("no pose rows in", results)
        return 1
    loops = list(dict.fromkeys(r["loop"] for r in poses))
    names = list(dict.fromkeys(r["pose"] for r in poses))
    fig, (ax_ap, ax_rp, ax_xy) = plt.subplots(1, 3, figsize=(15, 4.4))
    width = 0.8 / len(loops)
    for i, loop in enumerate(loops):
        rows = [r for r in poses if r["loop"] == loop]
        valid = all(r["valid"] == "1" for r in rows)
        x = np.arange(len(rows)) + (i - (len(loops) - 1) / 2) * width
        style = {} if valid else {"hatch": "//", "alpha": 0.5}
        label = loop if valid else f"{loop} (invalid)"
        ax_ap.bar(x, [float(r["ap_mm"]) for r in rows], width, label=label, **style)
        ax_rp.bar(x, [float(r["rp_mm"]) for r in rows], width, label=label, **style)
        pts = [r for r in arrivals if r["loop"] == loop]
        ax_xy.scatter([float(r["dx_mm"]) for r in pts], [float(r["dy_mm"]) for r in pts], s=8, label=label)
    for ax, title in ((ax_ap, "pose accuracy AP [mm]"), (ax_rp, "pose repeatability RP [mm]")):
        ax.set_xticks(np.arange(len(names)))
        ax.set_xticklabels(names)
        ax.set_title(title)
        ax.grid(axis="y", alpha=0.3)
    ax_ap.legend(fontsize=8)
    ax_xy.set_title("each arrival: attained - commanded (world x, y) [mm]")
    ax_xy.set_xlabel("x [mm]")
    ax_xy.set_ylabel("y [mm]")
    ax_xy.axhline(0, color="grey", lw=0.5)
    ax_xy.axvline(0, color="grey", lw=0.5)
    ax_xy.set_aspect("equal", adjustable="datalim")
    save_figure(fig, output, 110, title="ISO 9283 pose test, simulated arm (true end effector)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
