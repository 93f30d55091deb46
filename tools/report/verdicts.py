"""Verdicts on the paper's claims, generated from a run's statistics.

Every sentence here is assembled from the numbers it is given: the direction of the difference, the
p-value against ALPHA, the signed effect size with its direction in words, and the magnitude against
the paper's. Nothing in it is true regardless of the run: a run where torque mode loses gets a
different sentence from one where it wins.

Outcomes of one comparison (lower is better for every drop-test metric):
  reproduced    torque lower, p < ALPHA
  reversed      torque higher, p < ALPHA (the opposite of the paper)
  inconclusive  p >= ALPHA (or too few valid drops to test)
A claim's verdict: REPRODUCED or NOT REPRODUCED from its main setting, or DEPENDS ON <settings> when
another valid setting (a stabilisation band, the residual's reference, a sensitivity variant) gives a
different decisive outcome; a variant with fewer drops that is merely inconclusive does not count.
"""
import math

ALPHA = 0.05
MIN_VALID = 3  # valid drops per mode below which a setting is not tested


def _nan(x):
    return x is None or (isinstance(x, float) and math.isnan(x))


def outcome(s):
    if s["n_torque"] < MIN_VALID or s["n_position"] < MIN_VALID or _nan(s["p"]) or _nan(s["effect"]):
        return "inconclusive"
    if s["p"] >= ALPHA or s["effect"] == 0.0:
        return "inconclusive"
    return "reproduced" if s["effect"] > 0.0 else "reversed"


def _num(x, digits=3):
    if _nan(x):
        return "n/a"
    if x != 0.0 and (abs(x) < 1e-3 or abs(x) >= 1e4):
        return f"{x:.3e}"
    return f"{x:.{digits}f}"


def _centre(s, mode, unit):
    c = s[f"{mode}_centre"]
    if c is None:
        return f"not reached within {_num(s.get('horizon_s'))} {unit}"
    return f"{_num(c)} {unit}"


def effect_words(s):
    """The signed effect with its direction in words."""
    e = s["effect"]
    if _nan(e):
        return f"{s['effect_name']} effect size n/a"
    side = "lower" if s["effect_name"] != "Gehan pairwise" else "shorter"
    other = "higher" if side == "lower" else "longer"
    known = "" if s["effect_name"] != "Gehan pairwise" else " where the censoring leaves the order known"
    direction = ("in torque mode's favour" if e > 0 else "against torque mode" if e < 0 else "with no direction")
    return (f"signed {s['effect_name']} effect size {e:+.3f} ({direction}: torque {side} than position in "
            f"{100 * s['better_pairs']:.0f} % of drop pairs, {other} in {100 * s['worse_pairs']:.0f} %{known})")


def comparison_sentence(s, unit):
    """What this run measured for one comparison, in one sentence."""
    t, p = s["torque_centre"], s["position_centre"]
    lower, higher = ("shorter", "longer") if unit == "s" else ("lower", "higher")
    if t is None or p is None or _nan(t) or _nan(p):
        relation = "the two cannot be ordered by their centres"
    elif t < p:
        relation = f"torque {lower} by {_num(p - t)} {unit}" + (f" (ratio {t / p:.2f})" if p > 0 else "")
    elif t > p:
        relation = f"torque {higher} by {_num(t - p)} {unit}" + (f" (ratio {t / p:.2f})" if p > 0 else "")
    else:
        relation = "equal"
    censored = ""
    if s["censored_torque"] or s["censored_position"]:
        censored = (f"; not settled within the window: torque {s['censored_torque']} of {s['n_torque']}, "
                    f"position {s['censored_position']} of {s['n_position']}")
    return (f"torque {_centre(s, 'torque', unit)} vs position {_centre(s, 'position', unit)} ({s['centre']}s of "
            f"{s['n_torque']} / {s['n_position']} valid drops; {relation}{censored}), p = {_num(s['p'])}, "
            f"{effect_words(s)}")


def magnitude_sentence(s, paper, unit):
    """This run's magnitude against the paper's (paper: torque mean, sd, position mean, sd, p, |effect|)."""
    if paper is None:
        return ""
    pt, pp, pe = paper[0], paper[2], paper[5]
    parts = [f"paper: torque {pt} vs position {pp} {unit} (ratio {pt / pp:.2f}), p = {paper[4]:.1e}, effect +{pe}"]
    t, p = s["torque_centre"], s["position_centre"]
    if not (t is None or p is None or _nan(t) or _nan(p)) and p > 0:
        parts.append(f"here the ratio is {t / p:.2f} against the paper's {pt / pp:.2f}")
    if not _nan(s["effect"]):
        if s["effect"] <= 0:
            parts.append(f"the effect's sign is opposite to the paper's ({s['effect']:+.3f} vs +{pe})")
        else:
            size = "larger than" if s["effect"] > pe else "smaller than" if s["effect"] < pe else "equal to"
            parts.append(f"the effect is {size} the paper's ({s['effect']:+.3f} vs +{pe})")
    return "; ".join(parts)


def verdict_word(main, alternatives):
    """(verdict text, the alternative settings that decide a dependence)."""
    base = outcome(main)
    differing = []
    for name, s, same_drops in alternatives:
        o = outcome(s)
        if o != base and (same_drops or o != "inconclusive"):
            differing.append((name, o))
    if differing:
        groups = {}
        for name, o in [("the main setting", base)] + differing:
            groups.setdefault(o, []).append(name)
        detail = "; ".join(f"{o} with {', '.join(names)}" for o, names in groups.items())
        return f"DEPENDS ON {', '.join(n for n, _ in differing)} ({detail})", differing
    if base == "reproduced":
        return "REPRODUCED", []
    if base == "reversed":
        return "NOT REPRODUCED (torque mode significantly worse: the opposite of the paper)", []
    return f"NOT REPRODUCED (no significant difference at p < {ALPHA})", []


def claim_paragraph(claim, main, alternatives, paper, unit):
    """One paper claim: its verdict, this run's numbers, the paper's, and the settings that change it."""
    word, _ = verdict_word(main, alternatives)
    text = [f"Claim '{claim}': {word}.", f"This run: {comparison_sentence(main, unit)}."]
    mag = magnitude_sentence(main, paper, unit)
    if mag:
        text.append(mag[0].upper() + mag[1:] + ".")
    others = [f"{name}: {outcome(s)} (p = {_num(s['p'])}, effect {_num(s['effect'])}, "
              f"{s['n_torque']} / {s['n_position']} valid drops)" for name, s, _ in alternatives]
    if others:
        text.append("Other settings: " + "; ".join(others) + ".")
    return " ".join(text)


def parameter_range_sentence(main, by_parameter):
    """Per parameter swept over its plausible range (sensitivity rows grouped by parameter), whether
    the claim's outcome holds over the rows or flips: 'depends on <parameter>'. by_parameter maps a
    parameter to [(setting, statistics)]. A row whose outcome differs only by being inconclusive
    (fewer drops than the main table) does not count as a flip, as in verdict_word."""
    base = outcome(main)
    flips, holds = [], []
    for parameter, rows in by_parameter.items():
        outcomes = [(setting, outcome(s)) for setting, s in rows]
        differing = [(setting, o) for setting, o in outcomes if o != base and o != "inconclusive"]
        detail = ", ".join(f"{setting}: {o}" for setting, o in outcomes)
        if differing:
            flips.append(f"depends on {parameter} (main setting: {base}; {detail})")
        else:
            holds.append(f"{parameter} ({len(rows)} row{'s' if len(rows) != 1 else ''}: {detail})")
    parts = []
    if flips:
        parts.append("Over the plausible ranges: " + "; ".join(flips) + ".")
    if holds:
        parts.append(f"No flip of the main outcome ({base}) over " + "; ".join(holds) + ".")
    return " ".join(parts)
