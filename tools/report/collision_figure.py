#!/usr/bin/python3
"""Collision figure: the force a body region feels over time, peak force vs speed, v / v_max per link.

Usage: /usr/bin/python3 tools/report/collision_figure.py RESULTS_DIR OUTPUT.png

Reads what phri::run_collision writes into RESULTS_DIR:
  collision_runs.csv   one row per collision (region, motion, contact, mode, loop, constraint, peaks, ...)
  collision_trace.csv  run, t_after_touch_s, force_N, ... (every cycle from 0.1 s before the touch)
  collision_links.csv  run, link, max_ratio (each link's largest v / v_max before the touch)
Top: force vs time after the touch for the fastest point-to-point motion on the last region, free
and clamped, one colour per mode and loop (solid: without the constraint, dashed: with it), the
region's limit dotted. Bottom left: every free collision's peak force vs the tool's speed at the
touch, with the two-body model's F = v sqrt(mu k) for each region (mu from the median reflected
mass). Bottom middle: each link's largest v / v_max before the touch, without and with the
constraint. Bottom right: collisions over the limit per mode and loop. Invalid runs are left out.
Headless (Agg backend).
"""
import sys
from collections import defaultdict

from report_common import finish_axes, plt, read_rows, save_figure


def main(argv):
    if len(argv) != 3:
        print(__doc__)
        return 2
    results, output = argv[1], argv[2]
    runs = [r for r in read_rows(f"{results}/collision_runs.csv") if r["valid"] == "1"]
    if not runs:
        print("no valid collision in", results)
        return 1
    traces = defaultdict(lambda: ([], []))
    for row in read_rows(f"{results}/collision_trace.csv"):
        t, f = traces[row["run"]]
        t.append(1e3 * float(row["t_after_touch_s"]))
        f.append(float(row["force_N"]))
    links = read_rows(f"{results}/collision_links.csv")

    fig, axes = plt.subplots(2, 3, figsize=(17, 9))
    region = runs[-1]["region"]
    p2p = [r for r in runs if r["region"] == region and r["motion"] == "point_to_point"]
    fastest = max((float(r["nominal_speed_m_s"]) for r in p2p), default=None)
    pairs = sorted({(r["mode"], r["loop"]) for r in runs})
    colour = {pair: plt.cm.tab10(i % 10) for i, pair in enumerate(pairs)}
    for ax, contact in zip(axes[0][:2], ("free", "clamped")):
        shown = [r for r in p2p if r["contact"] == contact and float(r["nominal_speed_m_s"]) == fastest]
        for r in shown:
            t, f = traces[r["run"]]
            label = f"{r['mode']} / {r['loop']}" if r["constraint"] == "0" else None
            ax.plot(t, f, color=colour[(r["mode"], r["loop"])], linestyle="-" if r["constraint"] == "0" else "--",
                    linewidth=1.0, label=label)
        if shown:
            ax.axhline(float(shown[0]["limit_N"]), color="k", linestyle=":", label=f"limit {shown[0]['limit_N']} N")
        ax.set_xlim(-20, 300 if contact == "free" else 1000)
        finish_axes(ax, "time after the touch [ms]", "force on the body region [N]",
                    f"{region}, {contact}, point to point at {fastest} m/s (dashed: constraint on)", fontsize=6)

    ax = axes[0][2]
    clamped = [r for r in runs if r["contact"] == "clamped"]
    names = [f"{m}\n{l.replace('kinova_torque_high_velocity', 'kinova hv')}" for m, l in pairs]
    x = range(len(pairs))
    for offset, constraint, hatch in ((-0.2, "0", ""), (0.2, "1", "//")):
        worst = [max((float(r["quasi_static_force_N"]) for r in clamped
                      if (r["mode"], r["loop"]) == p and r["constraint"] == constraint), default=0.0) for p in pairs]
        ax.bar([i + offset for i in x], worst, width=0.4, hatch=hatch, edgecolor="k",
               label="without the constraint" if constraint == "0" else "with it")
    limits = sorted({float(r["quasi_static_limit_N"]) for r in clamped})
    for limit in limits:
        ax.axhline(limit, color="k", linestyle=":")
    ax.set_xticks(list(x))
    ax.set_xticklabels(names, fontsize=6, rotation=45)
    finish_axes(ax, "", "clamping force at the window's end [N]", "clamped: what stays (dotted: F_QS)", fontsize=7)

    ax = axes[1][0]
    for i, name in enumerate(dict.fromkeys(r["region"] for r in runs)):
        free = [r for r in runs if r["region"] == name and r["contact"] == "free"]
        for constraint, marker in (("0", "o"), ("1", "x")):
            sel = [r for r in free if r["constraint"] == constraint]
            ax.scatter([float(r["approach_speed_m_s"]) for r in sel], [float(r["peak_force_N"]) for r in sel], marker=marker,
                       color=plt.cm.tab10(i), s=14,
                       label=f"{name}{' (constraint on)' if constraint == '1' else ''}")
        if free:
            masses = sorted(float(r["reflected_mass_kg"]) for r in free)
            v_max, limit = float(free[0]["permissible_speed_m_s"]), float(free[0]["limit_N"])
            # F = v sqrt(mu k) = v limit / v_max at the median mass's v_max.
            median = masses[len(masses) // 2]
            at_median = [r for r in free if float(r["reflected_mass_kg"]) == median][0]
            slope = limit / float(at_median["permissible_speed_m_s"])
            top = max(float(r["approach_speed_m_s"]) for r in free)
            ax.plot([0, top], [0, slope * top], color=plt.cm.tab10(i), linewidth=0.8)
            ax.axhline(limit, color=plt.cm.tab10(i), linestyle=":")
    finish_axes(ax, "tool speed into the region at the touch [m/s]", "peak force [N]",
                "free contacts: peak force (lines: F = v sqrt(mu k); dotted: limit)", fontsize=7)

    ax = axes[1][1]
    region_runs = {r["run"]: r for r in runs if r["region"] == region}
    link_names = list(dict.fromkeys(l["link"] for l in links))
    for offset, constraint, hatch in ((-0.2, "0", ""), (0.2, "1", "//")):
        worst = []
        for name in link_names:
            values = [float(l["max_ratio"]) for l in links
                      if l["link"] == name and l["run"] in region_runs and region_runs[l["run"]]["constraint"] == constraint]
            worst.append(max(values, default=0.0))
        ax.bar([i + offset for i in range(len(link_names))], worst, width=0.4, hatch=hatch, edgecolor="k",
               label="without the constraint" if constraint == "0" else "with it")
    ax.axhline(1.0, color="k", linestyle=":")
    ax.set_xticks(range(len(link_names)))
    ax.set_xticklabels([n.replace("_link", "") for n in link_names], fontsize=6, rotation=45)
    finish_axes(ax, "", "largest v / v_max before the touch", f"{region}: per link (dotted: 1)", fontsize=7)

    ax = axes[1][2]
    for offset, constraint, hatch in ((-0.2, "0", ""), (0.2, "1", "//")):
        over = []
        for p in pairs:
            sel = [r for r in runs if (r["mode"], r["loop"]) == p and r["constraint"] == constraint]
            count = 0
            for r in sel:
                peak, limit = float(r["peak_force_N"]), float(r["limit_N"])
                held = r["contact"] == "clamped" and float(r["quasi_static_force_N"]) > float(r["quasi_static_limit_N"])
                count += 1 if peak > limit or held else 0
            over.append(count)
        ax.bar([i + offset for i in x], over, width=0.4, hatch=hatch, edgecolor="k",
               label="without the constraint" if constraint == "0" else "with it")
    ax.set_xticks(list(x))
    ax.set_xticklabels(names, fontsize=6, rotation=45)
    finish_axes(ax, "", "collisions over the limit", "per mode and loop (all regions and motions)", fontsize=7)

    save_figure(fig, output, 110, title="Simulated collisions with a body region (ISO/TS 15066 two-body model)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
