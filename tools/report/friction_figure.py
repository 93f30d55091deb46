#!/usr/bin/python3
"""Friction identification figure, after the paper's Fig. "friction" (torque error vs joint velocity).

Usage: /usr/bin/python3 tools/report/friction_figure.py RESULTS_DIR OUTPUT.png

Reads what phri::identify_friction writes into RESULTS_DIR:
  friction_samples.csv  joint, velocity_rad_s, torque_error_Nm   (raw samples, constant-current phases)
  friction_levels.csv   one row per current level (steady-state means, `steady` flag)
  friction_models.csv   one row per joint: identified and plant coulomb/viscous/static, fitted offset
  friction_form.csv     (optional; a plant of another form) its Stribeck velocity and exponent per joint:
                        the plant's dashed curve is then its true mean sliding friction
One panel per joint: the raw data shaded grey, the steady-state means, the identified model split
into its Coulomb part (green) and viscous part (yellow), the static estimate (red), and the
plant's true model (dashed). The torque sensor offset found by the fit is removed from the data.
Headless (Agg backend).
"""
import math
import os
import sys

import numpy as np
from report_common import plt, read_rows, save_figure


def plant_level(model, form, speed):
    """The plant's dry sliding level at |v| = speed: Coulomb, or its Stribeck curve (friction_model_form.hpp)."""
    tau_c = float(model["plant_coulomb_Nm"])
    if form is None or form["valid"] != "1" or float(form["stribeck_velocity_rad_s"]) <= 0.0:
        return np.full_like(speed, tau_c)
    tau_s = float(model["plant_static_Nm"])
    v_s, delta = float(form["stribeck_velocity_rad_s"]), float(form["stribeck_exponent"])
    return tau_c + (tau_s - tau_c) * np.exp(-(speed / v_s) ** delta)


def main(argv):
    if len(argv) != 3:
        print(__doc__)
        return 2
    results, output = argv[1], argv[2]
    samples = read_rows(f"{results}/friction_samples.csv")
    levels = read_rows(f"{results}/friction_levels.csv")
    models = read_rows(f"{results}/friction_models.csv")
    form_path = f"{results}/friction_form.csv"
    forms = {r["joint"]: r for r in read_rows(form_path)} if os.path.exists(form_path) else {}
    if not models:
        print("no identified joint in", results)
        return 1

    count = len(models)
    cols = min(4, count)
    rows = math.ceil(count / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
    for index, model in enumerate(models):
        ax = axes[index // cols][index % cols]
        joint = model["joint"]
        offset = float(model["offset_Nm"])
        tau_c = float(model["coulomb_Nm"])
        tau_v = float(model["viscous_Nms_per_rad"])
        tau_s = float(model["static_Nm"])
        plant_c = float(model["plant_coulomb_Nm"])
        plant_v = float(model["plant_viscous_Nms_per_rad"])

        v = np.array([float(r["velocity_rad_s"]) for r in samples if r["joint"] == joint])
        e = np.array([float(r["torque_error_Nm"]) for r in samples if r["joint"] == joint]) - offset
        ax.scatter(v, e, s=2, color="0.55", alpha=0.25, linewidths=0, label="data", rasterized=True)

        steady = [r for r in levels if r["joint"] == joint and r["steady"] == "1"]
        lv = np.array([float(r["velocity_rad_s"]) for r in steady])
        le = np.array([float(r["torque_error_Nm"]) for r in steady]) - offset
        ax.plot(lv, le, "o", color="black", markersize=3, label="steady state")

        vmax = max(np.abs(v).max() if v.size else 1.0, 0.1) * 1.05
        for sgn in (1.0, -1.0):
            x = np.linspace(0.0, vmax, 400) * sgn
            coulomb = np.full_like(x, sgn * tau_c)
            full = coulomb + tau_v * x
            ax.fill_between(x, coulomb, full, color="gold", alpha=0.45, linewidth=0,
                            label="viscous part" if sgn > 0 else None)
            ax.fill_between(x, 0.0, coulomb, color="tab:green", alpha=0.25, linewidth=0,
                            label="Coulomb part" if sgn > 0 else None)
            ax.plot(x, full, color="tab:olive", linewidth=1.5, label="identified model" if sgn > 0 else None)
            ax.plot(x, sgn * plant_level(model, forms.get(joint), np.abs(x)) + plant_v * x, "--", color="tab:blue",
                    linewidth=1.0, label="plant (truth, mean over position)" if sgn > 0 else None)
        ax.plot([0.0, 0.0], [-tau_s, tau_s], color="tab:red", linewidth=2.5, label="static estimate")
        ax.plot([0.0, 0.0], [-tau_s, tau_s], "_", color="tab:red", markersize=12, markeredgewidth=2.5)
        ax.axhline(0.0, color="0.8", linewidth=0.6)
        ax.axvline(0.0, color="0.8", linewidth=0.6)
        invalid = joint in forms and forms[joint]["valid"] != "1"
        ax.set_title(f"joint {joint} ({model['name']}): " + ("INVALID, not identified" if invalid else
                     f"{tau_c:.2f} sign(qd) + {tau_v:.2f} qd, static {tau_s:.2f}"), fontsize=9)
        ax.set_xlabel("joint velocity [rad/s]")
        ax.set_ylabel("torque error $K_T G_r i - \\tau_s$ [N.m]")
        ax.grid(alpha=0.3)
        if index == 0:
            ax.legend(fontsize=7, loc="upper left")
    for index in range(count, rows * cols):
        axes[index // cols][index % cols].axis("off")
    save_figure(fig, output, 130, "Friction identification (constant current at the upright stance; sensor offset removed)",
                11, "friction figure")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
