"""Drop test (phri experiment drop-test): statistics and figure.

Usage: drop_test_figure.py RESULTS_DIR OUTPUT.png

Reads RESULTS_DIR/drop_test_runs.csv (one row per drop) and drop_test_traces.csv (e_z after the
catch, one column per drop), prints the statistics of the paper's Table stat_analysis and draws the
paper's Fig. static-torque-position-comparison: every drop's error, torque mode on top, position
mode below.

Only valid drops count (the run's `valid` column: no safe stop, no QP fallback, the loop the mode
names); invalid ones are counted and listed, never averaged. Per metric:
  peak, residual, residual shift: Shapiro-Wilk per mode, two-sided Mann-Whitney U (normal
  approximation with tie correction), r = |Z| / sqrt(N) and the SIGNED rank-biserial correlation
  (P(torque < position) - P(torque > position) over all drop pairs: > 0 means torque mode lower,
  i.e. better, as every metric here is an error or a time).
  stabilisation, per absolute band: drops that did not settle are right-censored at the window's
  end minus its last second; per mode the count censored and the Kaplan-Meier median; the
  Gehan-Wilcoxon test (Mantel's permutation variance), Mann-Whitney generalised to censored data,
  and its signed pairwise effect (pairs whose order the censoring leaves unknown count as ties).
Headless (Agg); run by /usr/bin/python3 (numpy, scipy, matplotlib).
"""
import math
import os
import re
import sys

import numpy as np
from scipy import stats

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from report_common import plt, read_rows, save_figure  # noqa: E402

METRICS = [("peak_mm", "peak [mm]"), ("residual_mm", "residual [mm]"),
           ("residual_shift_mm", "residual shift from before the drop [mm]")]
# The paper's Table stat_analysis (torque mean, sd, position mean, sd, p, effect size). The paper
# prints its effect sizes unsigned; its text says torque mode is better on all three, so their sign
# toward torque is +.
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


def pair_fractions(x, y):
    """Over all pairs (x_i, y_j): the fraction with x < y and with x > y."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.size == 0 or y.size == 0:
        return float("nan"), float("nan")
    diff = x[:, None] - y[None, :]
    return float((diff < 0).mean()), float((diff > 0).mean())


def mann_whitney(x, y):
    """Two-sided Mann-Whitney U: (U of x, p, Z, r = |Z|/sqrt(N), signed rank-biserial toward x lower)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    n1, n2 = x.size, y.size
    if n1 == 0 or n2 == 0:
        return float("nan"), float("nan"), float("nan"), float("nan"), float("nan")
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
    return u1, p, z, abs(z) / math.sqrt(n), 1.0 - 2.0 * u1 / (n1 * n2)


def gehan_score(ti, ci, tj, cj):
    """+1 when observation i is certainly longer than j, -1 certainly shorter, 0 unknown or tied
    (t: time, c: censored, i.e. the true time is above t)."""
    if not ci and not cj:
        return float(np.sign(ti - tj))
    if ci and not cj:
        return 1.0 if ti >= tj else 0.0
    if cj and not ci:
        return -1.0 if tj >= ti else 0.0
    return 0.0


def gehan(tx, cx, ty, cy):
    """Gehan-Wilcoxon two-sample test with Mantel's variance: (p, Z, signed effect toward x shorter,
    fraction of pairs x certainly shorter, fraction certainly longer)."""
    t = list(tx) + list(ty)
    c = list(cx) + list(cy)
    n1, n2 = len(tx), len(ty)
    n = n1 + n2
    if n1 == 0 or n2 == 0:
        return float("nan"), float("nan"), float("nan"), float("nan"), float("nan")
    u = np.array([sum(gehan_score(t[i], c[i], t[j], c[j]) for j in range(n)) for i in range(n)])
    w = float(u[:n1].sum())  # sum over x of (certainly longer - certainly shorter) against y
    var = n1 * n2 / (n * (n - 1)) * float((u ** 2).sum()) if n > 1 else 0.0
    pairs = np.array([[gehan_score(tx[i], cx[i], ty[j], cy[j]) for j in range(n2)] for i in range(n1)])
    shorter, longer = float((pairs < 0).mean()), float((pairs > 0).mean())
    if var <= 0.0:
        return 1.0, 0.0, shorter - longer, shorter, longer
    z = w / math.sqrt(var)
    return float(2.0 * stats.norm.sf(abs(z))), z, shorter - longer, shorter, longer


def kaplan_meier_median(times, censored):
    """The Kaplan-Meier median (the first event time where survival falls to 0.5 or below); None when
    it is not reached (more than half still unsettled at the censoring time)."""
    order = np.argsort(times, kind="stable")
    t = np.asarray(times, dtype=float)[order]
    c = np.asarray(censored, dtype=bool)[order]
    at_risk, surv = len(t), 1.0
    for k in range(len(t)):
        if not c[k]:
            surv *= 1.0 - 1.0 / at_risk
            if surv <= 0.5 + 1e-12:
                return float(t[k])
        at_risk -= 1
    return None


def is_valid(r):
    return r.get("valid", "1") == "1"


def band_columns(rows):
    """The stabilisation bands the run measured: [(band_mm, time column, censored column)]; a run
    without per-band columns has its one stabilisation column, uncensored."""
    if not rows:
        return []
    out = []
    for col in rows[0]:
        if col is None:
            continue
        m = re.fullmatch(r"stabilisation_(\d+)p(\d+)mm_s", col)
        if m:
            out.append((float(f"{m.group(1)}.{m.group(2)}"), col, col.replace("stabilisation_", "censored_")[:-2]))
    return out or [(float("nan"), "stabilisation_s", None)]


def unpaired_metric(label, t, p):
    u, pval, z, r_eff, r_rb = mann_whitney(t, p)
    better, worse = pair_fractions(t, p)
    mean = lambda x: float(np.mean(x)) if len(x) else float("nan")  # noqa: E731
    sd = lambda x: float(np.std(x, ddof=1)) if len(x) > 1 else float("nan")  # noqa: E731
    return {"label": label, "torque_mean": mean(t), "torque_sd": sd(t), "position_mean": mean(p),
            "position_sd": sd(p), "torque_centre": mean(t), "position_centre": mean(p), "centre": "mean",
            "shapiro_torque": shapiro_p(t), "shapiro_position": shapiro_p(p), "U": u, "p": pval, "Z": z,
            "r": r_eff, "effect": r_rb, "effect_name": "rank-biserial", "better_pairs": better, "worse_pairs": worse,
            "n_torque": len(t), "n_position": len(p), "censored_torque": 0, "censored_position": 0}


def stabilisation_metric(rows, band, tcol, ccol):
    def side(mode):
        sel = [r for r in rows if r["mode"] == mode]
        t = [float(r[tcol]) for r in sel]
        c = [ccol is not None and r.get(ccol, "0") == "1" for r in sel]
        return t, c
    tt, tc = side("torque")
    pt, pc = side("position")
    pval, z, eff, shorter, longer = gehan(tt, tc, pt, pc)
    horizon = max(tt + pt) if tt + pt else float("nan")
    label = "stabilisation [s]" if math.isnan(band) else f"stabilisation, band {band:g} mm [s]"
    return {"label": label, "band_mm": band, "torque_centre": kaplan_meier_median(tt, tc),
            "position_centre": kaplan_meier_median(pt, pc), "centre": "Kaplan-Meier median", "horizon_s": horizon,
            "p": pval, "Z": z, "effect": eff, "effect_name": "Gehan pairwise", "better_pairs": shorter,
            "worse_pairs": longer, "n_torque": len(tt), "n_position": len(pt), "censored_torque": sum(tc),
            "censored_position": sum(pc)}


def drop_statistics(rows):
    """Per metric, on the valid drops: centres, spreads, test, signed effect; stabilisation per band
    (keys 'stabilisation_<band>'; 'stabilisation_s' is the first band's); 'validity' counts."""
    valid = [r for r in rows if is_valid(r)]
    out = {}
    for key, label in METRICS:
        if rows and key not in rows[0]:
            continue
        t = np.array([float(r[key]) for r in valid if r["mode"] == "torque"])
        p = np.array([float(r[key]) for r in valid if r["mode"] == "position"])
        out[key] = unpaired_metric(label, t, p)
    bands = []
    for band, tcol, ccol in band_columns(rows):
        s = stabilisation_metric(valid, band, tcol, ccol)
        bands.append(s)
        out.setdefault("stabilisation_s", s)
    out["bands"] = bands
    invalid = [r for r in rows if not is_valid(r)]
    out["validity"] = {"torque": sum(1 for r in valid if r["mode"] == "torque"),
                       "position": sum(1 for r in valid if r["mode"] == "position"),
                       "drops_torque": sum(1 for r in rows if r["mode"] == "torque"),
                       "drops_position": sum(1 for r in rows if r["mode"] == "position"),
                       "invalid": [(r["mode"], r["index"], r.get("invalid_reason", "")) for r in invalid]}
    return out


def fmt(x, digits=3):
    if x is None:
        return "n/a"
    if isinstance(x, float) and math.isnan(x):
        return "n/a"
    if x != 0.0 and (abs(x) < 1e-3 or abs(x) >= 1e4):
        return f"{x:.3e}"
    return f"{x:.{digits}f}"


def signed(x):
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:+.3f}"


def centre_text(s, mode):
    c = s[f"{mode}_centre"]
    if c is None:
        return f"not reached (> {fmt(s.get('horizon_s', float('nan')))})"
    if s["centre"] == "mean":
        return f"{fmt(c)} ± {fmt(s[f'{mode}_sd'])}"
    return fmt(c)


def statistics_table(st):
    """Markdown: simulation beside the paper, one row per metric (and per stabilisation band)."""
    lines = ["| metric | valid drops torque / position | torque (mean ± sd, or median) | position | censored torque / "
             "position | test | p (two-sided) | signed effect toward torque (+: torque lower) | paper torque | "
             "paper position | paper p | paper effect size |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    rows = [(k, st[k]) for k, _ in METRICS if k in st] + [("stabilisation_s", b) for b in st["bands"]]
    for key, s in rows:
        pp = PAPER.get(key)
        paper = [f"{pp[0]} ± {pp[1]}", f"{pp[2]} ± {pp[3]}", f"{pp[4]:.3e}", f"+{pp[5]}"] if pp else ["-"] * 4
        test = "Gehan-Wilcoxon" if s["effect_name"] == "Gehan pairwise" else "Mann-Whitney U"
        lines.append(f"| {s['label']} | {s['n_torque']} / {s['n_position']} | {centre_text(s, 'torque')} | "
                     f"{centre_text(s, 'position')} | {s['censored_torque']} / {s['censored_position']} | {test} | "
                     f"{fmt(s['p'])} | {signed(s['effect'])} ({s['effect_name']}) | " + " | ".join(paper) + " |")
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
