"""Drop test (phri experiment drop-test): statistics and figure.

Usage: drop_test_figure.py RESULTS_DIR OUTPUT.png

Reads RESULTS_DIR/drop_test_runs.csv (one row per drop) and drop_test_traces.csv (e_z after the
catch, one column per drop), prints the paper's statistics (Table stat_analysis) and draws the
paper's Fig. static-torque-position-comparison: every drop's error, torque mode on top, position
mode below. Statistics, per metric (peak, stabilisation, residual), as the paper describes them:
  Shapiro-Wilk per mode (normality; the paper chose the Mann-Whitney U test because one group was not
  normal), two-sided Mann-Whitney U (normal approximation with tie correction), and the effect size
  both ways: r = |Z| / sqrt(n1 + n2) and the rank-biserial correlation |1 - 2 U / (n1 n2)| (the
  paper's text names its effect size "rank-biserial correlation").
Headless (Agg); run by /usr/bin/python3 (numpy, scipy, matplotlib).
"""
import math
import os
import sys

import numpy as np
from scipy import stats

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from report_common import plt, read_rows, save_figure  # noqa: E402

METRICS = [("peak_mm", "peak [mm]"), ("stabilisation_s", "stabilisation [s]"), ("residual_mm", "residual [mm]")]
# The paper's Table stat_analysis (torque mean, sd, position mean, sd, p, effect size).
PAPER = {
    "peak_mm": (3.216, 0.594, 5.632, 1.820, 1.028e-06, 0.736),
    "stabilisation_s": (0.512, 0.226, 0.842, 0.220, 9.513e-04, 0.498),
    "residual_mm": (0.102, 0.061, 0.353, 0.025, 3.020e-11, 1.000),
}


def shapiro_p(x):
    """Shapiro-Wilk p-value; nan when the test is undefined (fewer than 3 values or all equal)."""
    x = np.asarray(x, dtype=float)
    if x.size < 3 or np.ptp(x) == 0.0:
        return float("nan")
    return float(stats.shapiro(x).pvalue)


def mann_whitney(x, y):
    """Two-sided Mann-Whitney U: (U of x, p, Z, r = |Z|/sqrt(N), rank-biserial)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    n1, n2 = x.size, y.size
    ranks = stats.rankdata(np.concatenate([x, y]))
    u1 = float(ranks[:n1].sum() - n1 * (n1 + 1) / 2.0)
    n = n1 + n2
    _, counts = np.unique(np.concatenate([x, y]), return_counts=True)
    ties = float(((counts ** 3) - counts).sum())
    sigma = math.sqrt(n1 * n2 / 12.0 * ((n + 1) - ties / (n * (n - 1)))) if n > 1 else 0.0
    if sigma == 0.0:
        return u1, 1.0, 0.0, 0.0, 0.0
    z = (u1 - n1 * n2 / 2.0) / sigma
    p = float(stats.mannwhitneyu(x, y, alternative="two-sided", method="asymptotic").pvalue)
    return u1, p, z, abs(z) / math.sqrt(n), abs(1.0 - 2.0 * u1 / (n1 * n2))


def drop_statistics(rows):
    """Per metric: dict with the means, sds, Shapiro-Wilk and Mann-Whitney results."""
    out = {}
    for key, label in METRICS:
        t = np.array([float(r[key]) for r in rows if r["mode"] == "torque"])
        p = np.array([float(r[key]) for r in rows if r["mode"] == "position"])
        u, pval, z, r_eff, r_rb = mann_whitney(t, p)
        out[key] = {"label": label, "torque_mean": t.mean(), "torque_sd": t.std(ddof=1) if t.size > 1 else 0.0,
                    "position_mean": p.mean(), "position_sd": p.std(ddof=1) if p.size > 1 else 0.0,
                    "shapiro_torque": shapiro_p(t), "shapiro_position": shapiro_p(p), "U": u, "p": pval, "Z": z,
                    "r": r_eff, "rank_biserial": r_rb, "n_torque": t.size, "n_position": p.size,
                    "torque_better": t.mean() < p.mean()}
    return out


def fmt(x, digits=3):
    if isinstance(x, float) and math.isnan(x):
        return "n/a"
    if x != 0.0 and (abs(x) < 1e-3 or abs(x) >= 1e4):
        return f"{x:.3e}"
    return f"{x:.{digits}f}"


def statistics_table(st):
    """Markdown: simulation beside the paper, one row per metric."""
    lines = ["| metric | torque mean ± sd | position mean ± sd | Shapiro-Wilk p (torque / position) | "
             "Mann-Whitney U | p (two-sided) | r = abs(Z)/sqrt(N) | rank-biserial | paper torque | paper position | "
             "paper p | paper effect size |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for key, _ in METRICS:
        s, pp = st[key], PAPER[key]
        lines.append(f"| {s['label']} | {fmt(s['torque_mean'])} ± {fmt(s['torque_sd'])} | "
                     f"{fmt(s['position_mean'])} ± {fmt(s['position_sd'])} | "
                     f"{fmt(s['shapiro_torque'])} / {fmt(s['shapiro_position'])} | {s['U']:.0f} | {fmt(s['p'])} | "
                     f"{fmt(s['r'])} | {fmt(s['rank_biserial'])} | {pp[0]} ± {pp[1]} | {pp[2]} ± {pp[3]} | "
                     f"{pp[4]:.3e} | {pp[5]} |")
    return "\n".join(lines)


def draw(results, output):
    rows = read_rows(f"{results}/drop_test_traces.csv")
    if not rows:
        return
    t = np.array([float(r["t_s"]) for r in rows])
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    for ax, mode, color in zip(axes, ("torque", "position"), ("tab:blue", "tab:orange")):
        columns = [c for c in rows[0] if c.startswith(mode + "_")]
        for c in columns:
            ax.plot(t, [float(r[c]) for r in rows], color=color, linewidth=0.6, alpha=0.5)
        ax.set_title(f"{mode} mode: {len(columns)} drops", fontsize=10)
        ax.set_ylabel("e_z = target - measured [mm]")
        ax.grid(alpha=0.3)
    axes[1].set_xlabel("time since the catch [s]")
    save_figure(fig, output, 120, "Drop test: end-effector error along z after the catch", 11, "drop test figure")


def main(argv):
    if len(argv) != 3:
        print(__doc__)
        return 2
    results, output = argv[1], argv[2]
    st = drop_statistics(read_rows(f"{results}/drop_test_runs.csv"))
    table = statistics_table(st)
    print(table)
    with open(f"{results}/drop_test_statistics.md", "w") as f:
        f.write(table + "\n")
    draw(results, output)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
