"""The friction identification on a plant of another form (Stribeck curve + position ripple): table and
sentences computed from friction_form.csv and friction_form_sweep.csv (phri::identify_friction with
--plant-friction stribeck-ripple; src/phri/experiments/friction_model_form.hpp defines the columns).

Every number of a sentence comes from the rows; a row with valid = 0 is counted, named with its reason,
and never enters a number.
"""

LARGE_ERROR = 0.10  # of the static level: the model "cannot fit" there (the same 10 % as the C++ side)


def _f(row, key):
    return float(row[key])


def _pct(x, of):
    return f"{100.0 * x / of:.1f} %" if of else "n/a"


def form_table(form_rows):
    """Markdown table of the per-joint comparison (invalid joints as such)."""
    lines = ["| joint | v_s [rad/s] | Fc plant / static [N.m] | Fc identified | Fv plant / identified [N.m.s/rad] | "
             "RMS err, levels' speeds | max err below the levels | err at breakaway speed | levels' scatter / ripple | "
             "unsteady levels |", "|" + "---|" * 10]
    for r in form_rows:
        if r["valid"] != "1":
            lines.append(f"| {r['joint']} | INVALID: {r['invalid_reason']} |" + " |" * 8)
            continue
        ts = _f(r, "plant_static_Nm")
        lines.append(
            f"| {r['joint']} | {_f(r, 'stribeck_velocity_rad_s'):.3f} | {_f(r, 'plant_coulomb_Nm'):.3f} / {ts:.3f} | "
            f"{_f(r, 'coulomb_Nm'):.3f} | {_f(r, 'plant_viscous_Nms_per_rad'):.3f} / {_f(r, 'viscous_Nms_per_rad'):.3f} | "
            f"{_f(r, 'rms_levels_Nm'):.3f} ({_pct(_f(r, 'rms_levels_Nm'), ts)}) | {_f(r, 'max_low_Nm'):.3f} "
            f"({_pct(_f(r, 'max_low_Nm'), ts)}) | {_f(r, 'error_at_breakaway_Nm'):.3f} | "
            f"{_f(r, 'level_scatter_max_Nm'):.3f} / {_f(r, 'ripple_Nm'):.3f} | {r['unsteady_levels']}/{r['levels_total']} |")
    return "\n".join(lines)


def form_sentences(form_rows):
    """One sentence group per joint."""
    out = []
    for r in form_rows:
        if r["valid"] != "1":
            out.append(f"Joint {r['joint']}: INVALID ({r['invalid_reason']}); its numbers are not results.")
            continue
        fc, tc, ts = _f(r, "coulomb_Nm"), _f(r, "plant_coulomb_Nm"), _f(r, "plant_static_Nm")
        if fc < tc:
            where = "below the plant's Coulomb level"
        elif fc > ts:
            where = "above the plant's static level"
        else:
            where = f"between the plant's Coulomb and static levels ({100.0 * (fc - tc) / (ts - tc):.0f} % of the way up)"
        text = (f"Joint {r['joint']}: the identified Coulomb level {fc:.3f} N.m lies {where} ({tc:.3f} / {ts:.3f} N.m). "
                f"Over the levels' speeds ({_f(r, 'slowest_level_rad_s'):.3f}-{_f(r, 'fastest_level_rad_s'):.3f} rad/s) "
                f"the model is off the plant's mean curve by {_f(r, 'rms_levels_Nm'):.3f} N.m RMS "
                f"({_pct(_f(r, 'rms_levels_Nm'), ts)} of static), below the slowest level by up to "
                f"{_f(r, 'max_low_Nm'):.3f} N.m ({_pct(_f(r, 'max_low_Nm'), ts)}); at the breakaway speed "
                f"({_f(r, 'breakaway_velocity_rad_s'):.4f} rad/s) its sign step is {_f(r, 'error_at_breakaway_Nm'):.3f} N.m "
                "off the curve.")
        below = _f(r, "ten_percent_below_rad_s")
        if below > 0.0:
            text += f" The model's form cannot fit below {below:.4f} rad/s (error > {100 * LARGE_ERROR:.0f} % of static)."
        else:
            text += f" Its error stays under {100 * LARGE_ERROR:.0f} % of static down to the breakaway speed."
        text += (f" The steady levels scatter about the true mean curve by up to {_f(r, 'level_scatter_max_Nm'):.3f} N.m "
                 f"(ripple amplitude {_f(r, 'ripple_Nm'):.3f} N.m); {r['unsteady_levels']} of {r['levels_total']} levels "
                 "were not steady and are not in the fit.")
        falls = _f(r, "negative_slope_below_rad_s") if "negative_slope_below_rad_s" in r else 0.0
        if falls > 0.0:
            text += (f" The plant's mean curve falls with speed below {falls:.3f} rad/s: no constant current holds a "
                     "speed there, so the protocol cannot sample that part of the curve.")
        out.append(text)
    return out


PARAMETER_NAMES = {"v_s": "v_s (Stribeck velocity, rad/s)", "a_r": "a_r (ripple amplitude, fraction of Coulomb)"}


def sweep_table(sweep_rows):
    lines = ["| parameter | value | joint | Fc identified (plant Fc / static) [N.m] | RMS err, levels' speeds | "
             "max err below the levels | off > 10 % of static below [rad/s] | unsteady levels |", "|" + "---|" * 8]
    for r in sweep_rows:
        head = f"| {r['sweep_parameter']} | {_f(r, 'sweep_value'):.3f} | {r['joint']} |"
        if r["valid"] != "1":
            lines.append(f"{head} INVALID: {r['invalid_reason']} | | | | |")
            continue
        ts = _f(r, "plant_static_Nm")
        lines.append(f"{head} {_f(r, 'coulomb_Nm'):.3f} ({_f(r, 'plant_coulomb_Nm'):.3f} / {ts:.3f}) | "
                     f"{_f(r, 'rms_levels_Nm'):.3f} ({_pct(_f(r, 'rms_levels_Nm'), ts)}) | {_f(r, 'max_low_Nm'):.3f} | "
                     f"{_f(r, 'ten_percent_below_rad_s'):.4f} | {r['unsteady_levels']}/{r['levels_total']} |")
    return "\n".join(lines)


def sweep_sentences(sweep_rows):
    """Per swept parameter and joint: how the fit error moves over the range (rows in sweep order)."""
    out = []
    groups = []
    for r in sweep_rows:
        if (r["sweep_parameter"], r["joint"]) not in groups:
            groups.append((r["sweep_parameter"], r["joint"]))
    for parameter, j in groups:
        name = PARAMETER_NAMES.get(parameter, parameter)
        rows = [r for r in sweep_rows if r["sweep_parameter"] == parameter and r["joint"] == j]
        valid = [r for r in rows if r["valid"] == "1"]
        invalid = len(rows) - len(valid)
        if len(valid) < 2:
            out.append(f"{name}, joint {j}: {len(valid)} valid run(s) of {len(rows)}: no trend to state.")
            continue
        rms = [_f(r, "rms_levels_Nm") for r in valid]
        rising = all(b >= a for a, b in zip(rms, rms[1:]))
        a, b = valid[0], valid[-1]
        worst = valid[max(range(len(rms)), key=lambda k: rms[k])]
        out.append(
            f"{name}, joint {j}: from {_f(a, 'sweep_value'):.3f} to {_f(b, 'sweep_value'):.3f} the RMS fit error over the "
            f"levels' speeds goes from {rms[0]:.3f} to {rms[-1]:.3f} N.m ({_pct(rms[0], _f(a, 'plant_static_Nm'))} to "
            f"{_pct(rms[-1], _f(b, 'plant_static_Nm'))} of static), "
            + ("rising at every step" if rising else
               f"not monotonically (largest {max(rms):.3f} N.m at {_f(worst, 'sweep_value'):.3f})")
            + f"; the speed below which the model is off by more than {100 * LARGE_ERROR:.0f} % of static goes from "
            f"{_f(a, 'ten_percent_below_rad_s'):.4f} to {_f(b, 'ten_percent_below_rad_s'):.4f} rad/s; unsteady levels go from "
            f"{a['unsteady_levels']} to {b['unsteady_levels']} of {b['levels_total']}; {invalid} invalid run(s) left out.")
    return out
