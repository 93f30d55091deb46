"""ctest `report_verdicts_follow_the_numbers`: the evaluation report's verdicts are computed, not canned.

Writes two synthetic drop-test result sets, one where torque mode wins every metric and one where it
loses every metric (plus an invalid drop and censored drops in each), runs the report generator
(tools/report/evaluation_report.py) on each, and checks that the verdict sentences differ
accordingly: REPRODUCED with the signs + in the first, NOT REPRODUCED with the signs - in the
second; the invalid drop is counted and left out; the censored drops are counted, not averaged.
Sensitivity rows grouped by parameter (sensitivity/variants.csv): a cable-stiffness row where the
outcome flips makes every claim say "depends on cable stiffness", a joint-stiffness row that agrees
does not. Torque-tracking summaries with an INVALID run: the run is flagged, its scenario gets no
verdict, the valid scenario gets one. Static torque tracking on six plants where the custom loop is lower
on every plant, or higher: the rank test's verdict is REPRODUCED, or NOT REPRODUCED in the opposite direction.

Usage: test_verdicts.py REPORT_SCRIPT WORK_DIR
"""
import os
import re
import shutil
import subprocess
import sys

import numpy as np

BANDS = ("0p25mm", "0p10mm", "0p50mm")


def write_runs(path, torque_better, seed):
    rng = np.random.default_rng(seed)
    header = ("mode,index,seed,catch_s,peak_mm,stabilisation_s,censored,residual_mm,before_mm,residual_shift_mm,"
              + ",".join(f"stabilisation_{b}_s,censored_{b}" for b in BANDS)
              + ",qp_fallbacks,safe_stop,loop_mismatch_cycles,loop_ran,valid,invalid_reason")
    lines = [header]
    good = {"peak": 3.0, "stab": 0.5, "res": 0.1}
    bad = {"peak": 6.0, "stab": 1.5, "res": 0.4}
    for mode in ("torque", "position"):
        m = good if (mode == "torque") == torque_better else bad
        for i in range(12):
            peak = m["peak"] * (1 + 0.1 * rng.standard_normal())
            res = m["res"] * (1 + 0.1 * rng.standard_normal())
            stab = m["stab"] * (1 + 0.1 * rng.standard_normal())
            # the loser's last two drops never settle: censored at 5 s
            cens = m is bad and i in (8, 9)
            t = 5.0 if cens else stab
            bands = ",".join(f"{t:.3f},{int(cens)}" for _ in BANDS)
            valid, why, loop = (0, "safe stop at 0.002 s (torque_current_mismatch; joint 2)", "position") \
                if (mode == "torque" and i == 11) else (1, "", "custom" if mode == "torque" else "position")
            lines.append(f"{mode},{i},{i + 1},6.2,{peak:.5f},{t:.3f},{int(cens)},{res:.5f},0.0,{res:.5f},{bands},"
                         f"0,{1 - valid},0,{loop},{valid},{why}")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def write_sensitivity(out):
    """Three rows: cable stiffness (same data, then the opposite data) and joint stiffness (same data)."""
    rows = [("cable_a", "cable stiffness", "cable 8000 N/m", True), ("cable_b", "cable stiffness", "cable 40000 N/m", False),
            ("joints_soft", "joint stiffness", "joints 4000 / 3500", True)]
    for name, _, _, better in rows:
        write_runs(f"{out}/sensitivity/{name}/drop_test_runs.csv", better, seed=11)
    with open(f"{out}/sensitivity/variants.csv", "w") as f:
        f.write("name,parameter,setting,source\n")
        for name, parameter, setting, _ in rows:
            f.write(f'{name},{parameter},"{setting}","no source, synthetic"\n')


def write_tracking(out):
    """Torque-tracking summary on elastic joints: static valid, dynamic with an INVALID custom run."""
    os.makedirs(f"{out}/torque_tracking", exist_ok=True)
    head = ("scenario,loop,rms_Nm,p95_Nm,max_Nm,bias_Nm,rms_true_Nm,p95_true_Nm,window_start_s,samples,ee_rms_mm,"
            "ee_y_rms_mm,ee_z_rms_mm,ee_vy_rms_mm_s,ee_vz_rms_mm_s,elastic,qp_fallbacks,safe_stop,loop_mismatch_cycles,"
            "loop_ran,valid,invalid_reason")
    lines = [head]
    for scen, loop, rms, valid in (("static", "custom", 0.1, 1), ("static", "kinova_torque_high_velocity", 0.3, 1),
                                   ("dynamic", "custom", 0.5, 0), ("dynamic", "kinova_torque_high_velocity", 0.9, 1)):
        why = "" if valid else "safe stop at 2.000 s (tracking_error; joint 4)"
        lines.append(f"{scen},{loop},{rms},{rms},{rms},0,{rms},{rms},0.5,1000,1,1,1,1,1,1,0,{1 - valid},0,"
                     f"{loop if valid else 'position'},{valid},{why}")
    with open(f"{out}/torque_tracking/torque_tracking_summary.csv", "w") as f:
        f.write("\n".join(lines) + "\n")


def write_tracking_seeds(out, custom_better):
    """The static scenario on six independent plants (seed 1 in torque_tracking/, seeds 2-6 beside it), the
    custom loop's RMS below the high-velocity loop's on every plant, or above it."""
    head = ("scenario,loop,rms_Nm,p95_Nm,max_Nm,bias_Nm,rms_true_Nm,p95_true_Nm,window_start_s,samples,ee_rms_mm,"
            "ee_y_rms_mm,ee_z_rms_mm,ee_vy_rms_mm_s,ee_vz_rms_mm_s,elastic,qp_fallbacks,safe_stop,loop_mismatch_cycles,"
            "loop_ran,valid,invalid_reason")
    for seed in range(1, 7):
        folder = f"{out}/torque_tracking" if seed == 1 else f"{out}/torque_tracking_seeds/seed_{seed}"
        os.makedirs(folder, exist_ok=True)
        low, high = 0.10 + 0.01 * seed, 0.30 + 0.01 * seed
        lines = [head]
        for loop, rms in (("custom", low if custom_better else high), ("kinova_torque_high_velocity", high if custom_better else low)):
            lines.append(f"static,{loop},{rms},{rms},{rms},0,{rms},{rms},0.5,1000,1,1,1,1,1,1,0,0,0,{loop},1,")
        with open(f"{folder}/torque_tracking_summary.csv", "w") as f:
            f.write("\n".join(lines) + "\n")


def run_report(script, out):
    run = subprocess.run(["/usr/bin/python3", script, out, "quick", "1.0"], capture_output=True, text=True, timeout=300)
    if run.returncode != 0:
        print(run.stdout, run.stderr)
        raise SystemExit(f"report generator exited with {run.returncode}")
    with open(f"{out}/report.md") as f:
        return f.read()


def claims(md):
    return [line for line in md.splitlines() if line.startswith("Claim '")]


def main(argv):
    script, work = argv[1], argv[2]
    shutil.rmtree(work, ignore_errors=True)  # no rows of an earlier run
    reports = {}
    for name, better in (("torque_wins", True), ("torque_loses", False)):
        out = f"{work}/{name}"
        write_runs(f"{out}/drop_test/drop_test_runs.csv", better, seed=7)
        write_tracking_seeds(out, better)
        reports[name] = run_report(script, out)
    ranges = f"{work}/ranges"  # torque wins in the main table; sensitivity rows and tracking runs
    write_runs(f"{ranges}/drop_test/drop_test_runs.csv", True, seed=7)
    write_sensitivity(ranges)
    write_tracking(ranges)
    ranges_md = run_report(script, ranges)
    failures = []
    win, lose = claims(reports["torque_wins"]), claims(reports["torque_loses"])
    drop_win = [c for c in win if "torque mode" in c]
    drop_lose = [c for c in lose if "torque mode" in c]
    if len(drop_win) != 3 or len(drop_lose) != 3:
        failures.append(f"expected 3 drop-test claims each, got {len(drop_win)} / {len(drop_lose)}")
    for a, b in zip(drop_win, drop_lose):
        if a == b:
            failures.append(f"identical verdict for opposite data: {a[:120]}")
        if ": REPRODUCED." not in a:
            failures.append(f"torque wins but not REPRODUCED: {a[:160]}")
        if "NOT REPRODUCED (torque mode significantly worse" not in b:
            failures.append(f"torque loses but not NOT REPRODUCED: {b[:160]}")
        if not re.search(r"effect size \+\d", a) or "in torque mode's favour" not in a:
            failures.append(f"torque wins without a positive signed effect: {a[:200]}")
        if not re.search(r"effect size -\d", b) or "against torque mode" not in b:
            failures.append(f"torque loses without a negative signed effect: {b[:200]}")
    for c in [c for c in claims(ranges_md) if "torque mode" in c]:
        if "depends on cable stiffness (main setting: reproduced" not in c or "cable 40000 N/m: reversed" not in c:
            failures.append(f"a flip inside the cable-stiffness range not stated: {c[-400:]}")
        if "No flip of the main outcome (reproduced) over joint stiffness (1 row" not in c:
            failures.append(f"an agreeing joint-stiffness row not stated as holding: {c[-400:]}")
    md = ranges_md
    tracking = [line for line in md.splitlines() if line.startswith("Claim 'the custom loop")]
    if len(tracking) != 1 or "(static, elastic joints)" not in tracking[0] or "HV / custom = 3.00" not in tracking[0]:
        failures.append(f"expected one torque-tracking verdict, static on elastic joints: {tracking}")
    if "INVALID: custom torque: safe stop at 2.000 s" not in md or "Tracking runs: 1 of 4 INVALID" not in md:
        failures.append("the invalid dynamic custom run is not flagged in the table and the header")
    seeded = {name: [c for c in claims(md) if c.startswith("Claim 'the custom loop")] for name, md in reports.items()}
    if len(seeded["torque_wins"]) != 1 or ": REPRODUCED: 6 / 6 valid runs on independent plants" not in seeded["torque_wins"][0] \
            or "the paper's direction" not in seeded["torque_wins"][0]:
        failures.append(f"custom lower on six plants but not REPRODUCED by the test: {seeded['torque_wins']}")
    if len(seeded["torque_loses"]) != 1 or ": NOT REPRODUCED: 6 / 6 valid runs" not in seeded["torque_loses"][0] \
            or "the opposite of the paper's direction" not in seeded["torque_loses"][0]:
        failures.append(f"custom higher on six plants but not stated as the opposite: {seeded['torque_loses']}")
    for name, md in reports.items():
        if "1 of 24 drops INVALID" not in md:
            failures.append(f"{name}: the header does not count the invalid drop")
        if "11 of 12 torque drops" not in md:
            failures.append(f"{name}: the invalid drop is not left out of the counts")
        loser = "torque" if name == "torque_loses" else "position"
        n = 11 if loser == "torque" else 12
        if f"{loser} 2 of {n}" not in md:
            failures.append(f"{name}: the censored drops of the {loser} mode are not reported as 2 of {n}")
    for f in failures:
        print("FAIL:", f)
    for c in drop_win + drop_lose:
        print(c[:300])
    print(f"verdicts checked: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
