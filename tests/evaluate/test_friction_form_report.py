"""ctest `report_friction_form_follows_the_numbers`: the friction-form part of the evaluation report
(tools/report/friction_form_report.py) computes its sentences from the rows.

Synthetic rows of friction_form.csv and friction_form_sweep.csv: a joint whose fit error rises over the
v_s sweep and one whose error does not (plus an invalid run), a valid joint and an invalid one. The
sentences must carry the rows' numbers, say "rising" only where it rises, count the invalid runs and
never give an invalid row's numbers.

Usage: test_friction_form_report.py TOOLS_REPORT_DIR
"""
import sys

FORM_KEYS = ("stribeck_velocity_rad_s,stribeck_exponent,ripple_Nm,breakaway_velocity_rad_s,slowest_level_rad_s,"
             "fastest_level_rad_s,rms_levels_Nm,max_levels_Nm,max_levels_at_rad_s,rms_low_Nm,max_low_Nm,"
             "error_at_breakaway_Nm,ten_percent_below_rad_s,level_scatter_rms_Nm,level_scatter_max_Nm,unsteady_levels").split(",")


def form_row(joint, valid, **values):
    row = {k: "0" for k in FORM_KEYS}
    row.update({"joint": str(joint), "name": f"joint_{joint}", "valid": "1" if valid else "0",
                "invalid_reason": "" if valid else "only 2 steady levels of 24", "plant_coulomb_Nm": "1.6",
                "plant_static_Nm": "1.92", "plant_viscous_Nms_per_rad": "1.36", "coulomb_Nm": "1.7",
                "viscous_Nms_per_rad": "1.3", "static_Nm": "1.9", "levels_used": "20", "levels_total": "24",
                "breakaway_velocity_rad_s": "0.001"})
    row.update({k: str(v) for k, v in values.items()})
    return row


def sweep_row(v_s, joint, rms, valid=True, parameter="v_s"):
    row = form_row(joint, valid, rms_levels_Nm=rms, max_low_Nm=0.3, ten_percent_below_rad_s=v_s / 2)
    row["sweep_parameter"], row["sweep_value"] = parameter, str(v_s)
    return row


def main(argv):
    sys.path.insert(0, argv[1])
    from friction_form_report import form_sentences, form_table, sweep_sentences, sweep_table

    failures = []

    def check(condition, what):
        if not condition:
            failures.append(what)
            print("FAIL:", what)

    form = [form_row(5, True, stribeck_velocity_rad_s=0.02, rms_levels_Nm=0.0123, max_low_Nm=0.2345,
                     error_at_breakaway_Nm=-0.2211, ten_percent_below_rad_s=0.0312, level_scatter_max_Nm=0.0456,
                     ripple_Nm=0.16, slowest_level_rad_s=0.05, fastest_level_rad_s=0.9, unsteady_levels=3),
            form_row(6, False, rms_levels_Nm=9.999)]
    sentences = form_sentences(form)
    check(len(sentences) == 2, "one sentence group per joint")
    s5, s6 = sentences
    check("1.700 N.m lies between the plant's Coulomb and static levels (31 % of the way up)" in s5,
          "Coulomb placement computed: (1.7 - 1.6) / (1.92 - 1.6) = 31 %")
    check("0.012 N.m RMS (0.6 % of static)" in s5, "RMS error and its % of static from the row")
    check("up to 0.234 N.m (12.2 %)" in s5, "low-speed error from the row")
    check("cannot fit below 0.0312 rad/s" in s5, "the speed where the model's form fails")
    check("3 of 24 levels were not steady" in s5, "unsteady levels counted")
    check("INVALID" in s6 and "9.999" not in s6, "an invalid joint is named, its numbers not given")
    table = form_table(form)
    check("INVALID: only 2 steady levels of 24" in table and "9.999" not in table, "invalid row in the table")
    no_large = form_sentences([form_row(5, True, ten_percent_below_rad_s=0.0, slowest_level_rad_s=0.05)])[0]
    check("stays under 10 % of static" in no_large, "no 'cannot fit' where the error never exceeds 10 %")

    sweep = [sweep_row(0.005, 1, 0.001), sweep_row(0.02, 1, 0.01), sweep_row(0.1, 1, 0.08),
             sweep_row(0.005, 5, 0.004), sweep_row(0.02, 5, 0.002), sweep_row(0.05, 5, 7.77, valid=False),
             sweep_row(0.1, 5, 0.03)]
    j1, j5 = sweep_sentences(sweep)
    check("from 0.001 to 0.080 N.m" in j1 and "rising at every step" in j1 and "0 invalid" in j1, "joint 1 rises")
    check("goes from 0.0025 to 0.0500 rad/s" in j1, "the 10 % speed from the first and last valid rows")
    check("not monotonically" in j5 and "rising" not in j5, "joint 5 does not rise monotonically")
    check("largest 0.030 N.m at 0.100" in j5, "the largest error and its value")
    check("1 invalid run(s) left out" in j5 and "7.77" not in j5, "the invalid run counted, not used")
    check("INVALID" in sweep_table(sweep) and "7.770" not in sweep_table(sweep), "invalid run in the sweep table")
    lonely = sweep_sentences([sweep_row(0.02, 3, 0.01), sweep_row(0.1, 3, 0.02, valid=False)])[0]
    check("1 valid run(s) of 2" in lonely and "no trend" in lonely, "no trend claimed from one valid run")
    both = sweep_sentences([sweep_row(0.02, 3, 0.01), sweep_row(0.1, 3, 0.02),
                            sweep_row(0.0, 3, 0.02, parameter="a_r"), sweep_row(0.2, 3, 0.01, parameter="a_r")])
    check(len(both) == 2 and both[0].startswith("v_s") and both[1].startswith("a_r") and "not monotonically" in both[1],
          "one sentence per swept parameter and joint")

    print(f"friction form report checked: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
