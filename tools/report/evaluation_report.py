"""The report of `phri evaluate`: report.md and a self-contained report.html (figures inline, base64 PNG).

Usage: evaluation_report.py OUTPUT_DIR (quick|full) WALL_SECONDS

Reads what the five evaluations wrote into OUTPUT_DIR (friction_identification/, torque_tracking/,
drop_test/, sensitivity/*/, dynamic_tracking/, dual_compliance/), draws the figures the experiments
did not, and writes one document: per evaluation the metric definitions, the simulation's table beside
the paper's numbers and, wherever they differ, a sentence saying why. Headless; /usr/bin/python3.
"""
import base64
import html
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from drop_test_figure import PAPER as DROP_PAPER  # noqa: E402
from drop_test_figure import draw as draw_drop  # noqa: E402
from drop_test_figure import drop_statistics, fmt, statistics_table  # noqa: E402
from report_common import plt, read_rows, save_figure  # noqa: E402

# The paper's friction model, eq. friction-model: tau_f = Fc sign(qd) + Fv qd.
PAPER_FRICTION = {"large": (2.15, 2.00), "small": (1.60, 1.36)}
LOOP_NAMES = {"position": "position", "custom": "custom torque", "kinova_torque": "Kinova torque",
              "kinova_torque_high_velocity": "Kinova high-velocity"}


class Report:
    """Blocks rendered twice: markdown and HTML."""

    def __init__(self, out):
        self.out, self.blocks = out, []

    def h(self, level, text):
        self.blocks.append(("h", level, text))

    def p(self, text):
        self.blocks.append(("p", text))

    def table(self, markdown):
        self.blocks.append(("table", markdown))

    def figure(self, path, caption):
        if os.path.exists(path):
            self.blocks.append(("img", path, caption))
        else:
            self.p(f"(figure {os.path.basename(path)} missing)")

    def markdown(self):
        parts = []
        for b in self.blocks:
            if b[0] == "h":
                parts.append("#" * b[1] + " " + b[2])
            elif b[0] == "p":
                parts.append(b[1])
            elif b[0] == "table":
                parts.append(b[1])
            else:
                parts.append(f"![{b[2]}]({os.path.relpath(b[1], self.out)})\n\n*{b[2]}*")
        return "\n\n".join(parts) + "\n"

    def html(self):
        body = []
        for b in self.blocks:
            if b[0] == "h":
                body.append(f"<h{b[1]}>{html.escape(b[2])}</h{b[1]}>")
            elif b[0] == "p":
                body.append(f"<p>{html.escape(b[1])}</p>")
            elif b[0] == "table":
                body.append(table_html(b[1]))
            else:
                with open(b[1], "rb") as f:
                    data = base64.b64encode(f.read()).decode("ascii")
                body.append(f'<figure><img src="data:image/png;base64,{data}" alt="{html.escape(b[2])}">'
                            f"<figcaption>{html.escape(b[2])}</figcaption></figure>")
        style = ("body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}"
                 "table{border-collapse:collapse;margin:1em 0;font-size:90%}td,th{border:1px solid #999;padding:3px 6px}"
                 "img{max-width:100%}figcaption{font-style:italic;font-size:90%}")
        return ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>phri evaluation</title>"
                f"<style>{style}</style></head><body>\n" + "\n".join(body) + "\n</body></html>\n")


def table_html(markdown):
    rows = [r.strip().strip("|").split("|") for r in markdown.strip().splitlines()]
    rows = [r for r in rows if not all(set(c.strip()) <= set("-:") for c in r)]
    head = "".join(f"<th>{html.escape(c.strip())}</th>" for c in rows[0])
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c.strip())}</td>" for c in r) + "</tr>" for r in rows[1:])
    return f"<table><tr>{head}</tr>{body}</table>"


def md_table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def friction_section(rep, out):
    d = f"{out}/friction_identification"
    rep.h(2, "1. Friction identification")
    rep.p("Protocol (paper, 'Friction parameters identification'): the arm upright (no gravity torque), one joint at a "
          "time at constant motor current, the others held; per level the steady velocity and the torque error "
          "K_T G_r i - tau_s; least squares for Coulomb + viscous (+ the torque sensor's offset), a bisection on the "
          "breakaway current for static friction. Metric: identified coefficients against the plant's true ones.")
    models = read_rows(f"{d}/friction_models.csv") if os.path.exists(f"{d}/friction_models.csv") else []
    rows = []
    for m in models:
        size = "large" if int(m["joint"]) <= 4 else "small"
        fc, fv = PAPER_FRICTION[size]
        rows.append([m["joint"], size, f"{float(m['coulomb_Nm']):.3f}", f"{float(m['plant_coulomb_Nm']):.3f}", f"{fc:.2f}",
                     f"{float(m['viscous_Nms_per_rad']):.3f}", f"{float(m['plant_viscous_Nms_per_rad']):.3f}", f"{fv:.2f}",
                     f"{float(m['static_Nm']):.3f}", f"{float(m['plant_static_Nm']):.3f}"])
    rep.table(md_table(["joint", "actuator", "Fc identified [N.m]", "Fc plant", "Fc paper", "Fv identified [N.m.s/rad]",
                        "Fv plant", "Fv paper", "Fs identified [N.m]", "Fs plant"], rows))
    rep.p("Why simulation and paper differ: the plant's friction is the paper's identified model (eq. friction-model) "
          "with every coefficient moved by up to 20 % (seeded), so that the identification has something to find; "
          "the identified values are to be compared with the plant's column, the paper's column is where the plant "
          "started from. The paper lumps static and Coulomb friction; the plant keeps them equal too.")
    rep.figure(f"{d}/friction_identification.png", "Friction identification: torque error against velocity, fitted models")


def torque_tracking_section(rep, out):
    d = f"{out}/torque_tracking"
    rep.h(2, "2. Torque tracking (static and dynamic)")
    rep.p("Metric: ||tau_d[k] - tau_s[k+1]|| over the 7 joints (the QP's desired torque against the torque sensors at "
          "the end of the period it was in force), RMS and 95th percentile after a 0.5 s transient; static: demo "
          "posture, 1.25 kg on the tool, stiff end effector; dynamic: the demo's y-z scenario (z sine 0.1 m at 3 rad/s, "
          "y triangle at 0.1 m/s), null-space compliance.")
    summary = read_rows(f"{d}/torque_tracking_summary.csv") if os.path.exists(f"{d}/torque_tracking_summary.csv") else []
    by = {(r["scenario"], r["loop"]): r for r in summary}
    rows = []
    for scen in ("static", "dynamic"):
        c, hv = by.get((scen, "custom")), by.get((scen, "kinova_torque_high_velocity"))
        if c is None or hv is None:
            continue
        ratio = float(hv["rms_Nm"]) / float(c["rms_Nm"])
        rows.append([scen, f"{float(c['rms_Nm']):.4f}", f"{float(c['p95_Nm']):.4f}", f"{float(hv['rms_Nm']):.4f}",
                     f"{float(hv['p95_Nm']):.4f}", f"{ratio:.2f}", "custom below Kinova HV (Fig. torque-control-results, "
                     "log scale; no numbers given)"])
    elastic = f"{out}/torque_tracking_elastic/torque_tracking_summary.csv"
    if os.path.exists(elastic):
        e = {(r["scenario"], r["loop"]): r for r in read_rows(elastic)}
        c, hv = e.get(("static", "custom")), e.get(("static", "kinova_torque_high_velocity"))
        if c is not None and hv is not None:
            ratio = float(hv["rms_Nm"]) / float(c["rms_Nm"])
            rows.append(["static, elastic joints", f"{float(c['rms_Nm']):.4f}", f"{float(c['p95_Nm']):.4f}",
                         f"{float(hv['rms_Nm']):.4f}", f"{float(hv['p95_Nm']):.4f}", f"{ratio:.2f}", "(same figure)"])
    rep.table(md_table(["scenario", "custom RMS [N.m]", "custom p95", "Kinova HV RMS", "Kinova HV p95", "HV / custom",
                        "paper"], rows))
    static = [r for r in rows if r[0].startswith("static")]
    if static and min(float(r[5]) for r in static) < 1.5:
        rep.p("Why the static ratio is near 1 here: at rest the inverse dynamics subtracts the observer's tau_ext, which "
              "converges to g - tau_s, so tau_d follows the sensors whatever loop runs; the loops differ only when joints "
              "slide, i.e. through friction, and with the paper's 1.25 kg on the tool no joint slides in either loop. "
              "The paper shows a clear gap in its static figure; its arm evidently moved or rang where this rigid "
              "plant rests.")
    elastic_rows = [r for r in rows if r[0] == "static, elastic joints"]
    if elastic_rows:
        ratio = float(elastic_rows[0][5])
        rep.p(f"Static scenario on the elastic plant (springs between rotor and link, torque sensors measuring them; "
              f"run without retuning anything): Kinova HV / custom = {ratio:.2f}. "
              + ("The custom loop does worse there: its error rings at about 50 Hz on joint 2 (the spectrum of "
                 "torque_tracking_elastic/torque_tracking_static_custom.csv), an interaction of its transfer-function "
                 "feedback lambda H(z) and friction pre-compensation with the drive's spring that the paper's real arm "
                 "evidently does not show; the gains were identified on the real (elastic) arm, so the plant's "
                 "spring, damping or rotor-side friction model is the suspect; nothing was tuned to hide it."
                 if ratio < 1.0 else "The custom loop keeps its advantage on the elastic plant."))
    rep.figure(f"{d}/torque_tracking.png", "Torque tracking error, custom vs Kinova high-velocity loop")


def drop_section(rep, out):
    d = f"{out}/drop_test"
    rep.h(2, "3. Drop test: torque vs position mode")
    rep.p("Protocol (paper, 'Stiffness in static configurations'; issue 15): the arm half extended forward holds the "
          "6-D pose of its end effector; a 1.25 kg weight held by a hand under the tool is let go (t = 6 s; quick: 2 s; "
          "the fall height and sideways offset vary by +-2 cm / +-1 cm per drop) and caught by a 25 cm cable anchored "
          "on the tool; drop i uses noise seed i and mismatch seed 1000 + i. Torque mode: custom low-level loop, stiff "
          "end-effector task (K 400), null-space compliance, the paper code's external torque (momentum observer "
          "K_O = 10 plus the high-pass of J^T F/T, complementary filter). Position mode: as the paper's mc_rtc, the QP "
          "runs on its own state integrated open loop and the vendor position servo tracks it. Plant: elastic joints "
          "(harmonic-drive springs between rotor and link, torque sensors measuring them; the servo closes on the "
          "motor encoder).")
    rep.p("Metrics over 6 s after the catch (cable taut, what the paper's F/T sensor synchronises on), e = target - "
          "measured end-effector z: peak = max |e|; residual = |mean of e over the last second|; stabilisation = time "
          "from the catch until e stays within 5 % of the peak around that mean (the paper does not state its band). "
          "Statistics: Shapiro-Wilk per group, two-sided Mann-Whitney U, effect size r = |Z|/sqrt(N) and the "
          "rank-biserial correlation (the paper's 'effect size').")
    runs = read_rows(f"{d}/drop_test_runs.csv")
    st = drop_statistics(runs)
    st["traces"] = trace_summary(d)
    rep.table(statistics_table(st))
    verdicts = []
    for key, label in (("peak_mm", "peak"), ("stabilisation_s", "stabilisation"), ("residual_mm", "residual")):
        s = st[key]
        ok = s["torque_better"] and s["p"] < 0.01
        verdicts.append(ok)
        rep.p(f"{label}: torque {'better' if s['torque_better'] else 'worse'} than position "
              f"({fmt(s['torque_mean'])} vs {fmt(s['position_mean'])}), p = {fmt(s['p'])}: the paper's claim "
              f"{'holds' if ok else 'does not hold'} here.")
    rep.p(drop_explanation(st))
    if not os.path.exists(f"{d}/drop_test.png"):
        draw_drop(d, f"{d}/drop_test.png")
    rep.figure(f"{d}/drop_test.png", "Drop test: e_z of every drop after the catch (paper Fig. static-torque-position)")
    sensitivity_section(rep, out)
    return st


def trace_summary(d):
    """Per mode, from the traces: the error at the catch (before the shock reaches the arm) and the
    error's standard deviation over the last second, averaged over drops [mm]."""
    rows = read_rows(f"{d}/drop_test_traces.csv")
    t = np.array([float(r["t_s"]) for r in rows])
    last = t >= t[-1] - 1.0
    out = {}
    for mode in ("torque", "position"):
        cols = [c for c in rows[0] if c.startswith(mode + "_")]
        series = [np.array([float(r[c]) for r in rows]) for c in cols]
        out[mode] = {"at_catch": float(np.mean([x[0] for x in series])) if series else float("nan"),
                     "tail_sd": float(np.mean([np.std(x[last]) for x in series])) if series else float("nan"),
                     "shift": float(np.mean([np.mean(x[last]) - x[0] for x in series])) if series else float("nan")}
    return out


def drop_explanation(st):
    """Why the simulated drop test differs from the paper, from the plant's physics."""
    tr = st["traces"]
    parts = [f"Error before the shock (at the catch): torque {tr['torque']['at_catch']:.3f} mm, position "
             f"{tr['position']['at_catch']:.3f} mm; the last second's mean minus it (the weight's own static effect): "
             f"torque {tr['torque']['shift']:.3f} mm, position {tr['position']['shift']:.3f} mm."]
    parts.append("Position mode: the paper's mc_rtc integrates the QP's own state open loop into the vendor servo, "
                 "which closes on the motor-side encoder behind the harmonic drive's spring (K 1.3e4 N.m/rad large, "
                 "5.5e3 small actuators): the servo's integrator brings the rotors back, but the links stay deflected "
                 "by tau / K, under the arm's own weight before the drop and by the 1.25 kg weight after it. That "
                 "deflection is the position residual; no feedback sees it (the QP's state is its own). Torque mode "
                 "closes on the link-side joint positions and the F/T sensor and returns to its target.")
    if not (st["peak_mm"]["torque_better"] and st["peak_mm"]["p"] < 0.01):
        parts.append("Peak: torque mode rejects the catch only as fast as its external-torque estimate; see the "
                     "sensitivity rows with the observer alone.")
    else:
        parts.append("Peak: the F/T sensor's fast part of the fused estimate cancels the catch within a cycle in torque "
                     "mode; the position servo, behind the joints' springs, lets the catch through (the observer alone "
                     "at K_O = 10 is far slower: see the sensitivity table).")
    if not (st["stabilisation_s"]["torque_better"] and st["stabilisation_s"]["p"] < 0.01):
        parts.append("Stabilisation: the band is relative (5 % of each drop's own peak): torque mode's small peak gives "
                     f"a band of about {0.05 * st['peak_mm']['torque_mean']:.3f} mm, while its error keeps moving with "
                     f"a standard deviation of {tr['torque']['tail_sd']:.3f} mm in the last second (position "
                     f"{tr['position']['tail_sd']:.3f} mm): the mass keeps swinging on its 25 cm cord (a pendulum at "
                     "1.0 Hz, started by the hand's sideways release offset, loading the tool at twice that), which the "
                     "stiff position servo hardly shows and the torque-controlled end effector (K 400 1/s^2, through "
                     "its estimate) does. The row without release spread (no swing) shortens it. The cord (2000 N/m, "
                     "damping ratio 0.1) also bounces the mass for about 1.5 s in both modes.")
    return " ".join(parts)


def sensitivity_section(rep, out):
    base = f"{out}/sensitivity"
    if not os.path.isdir(base):
        rep.p("Sensitivity table: not run (--quick).")
        return
    rep.h(3, "Sensitivity: the drop test with one setting changed")
    rep.p("Fewer drops per variant (see the counts) released at 3 s; same seeds as the main table; each row changes one thing from the "
          "main table's setting: the external-torque source and observer gain, the cable damping (50 N.s/m: damping "
          "ratio 0.5), the vendor servo gains (x 0.5), no release spread, the weight latched on the tool (the arm "
          "carries it until the release), rigid joints, the servo on the link-side encoder, softer joints (4000 / 3500 "
          "N.m/rad, a Gen3 impedance controller's tuned values), the position-mode QP on the measured state.")
    rows, by_name = [], {}
    for name in sorted(os.listdir(base)):
        path = f"{base}/{name}/drop_test_runs.csv"
        if not os.path.exists(path):
            continue
        st = drop_statistics(read_rows(path))
        by_name[name] = st
        row = [name, str(st["peak_mm"]["n_torque"])]
        for key in ("peak_mm", "stabilisation_s", "residual_mm"):
            s = st[key]
            row.append(f"{fmt(s['torque_mean'])} / {fmt(s['position_mean'])} (p {fmt(s['p'])})")
        rows.append(row)
    rep.table(md_table(["variant", "drops per mode", "peak torque / position [mm]", "stabilisation [s]",
                        "residual [mm]"], rows))
    rep.p(sensitivity_reading(by_name))


def sensitivity_reading(by_name):
    """What decides each metric, read off the sensitivity rows (sentences only for rows present)."""
    def m(name, key, mode):
        return by_name[name][key][f"{mode}_mean"]
    out = []
    if "observer_only_K10" in by_name:
        out.append(f"Peak: decided by the external-torque source. With the observer alone at the paper code's K_O = 10 "
                   f"the torque-mode peak is {m('observer_only_K10', 'peak_mm', 'torque'):.1f} mm (position "
                   f"{m('observer_only_K10', 'peak_mm', 'position'):.1f} mm): the catch is cancelled only through the "
                   "observer's lag; the F/T sensor's high-pass part (fused) is what makes torque mode win.")
    if "rigid_joints" in by_name:
        out.append(f"Residual: decided by the joints' elasticity behind a motor-side servo and the open-loop QP. "
                   f"With rigid joints the position residual is {m('rigid_joints', 'residual_mm', 'position'):.3f} mm "
                   f"(torque {m('rigid_joints', 'residual_mm', 'torque'):.3f} mm): position mode wins.")
    if "position_qp_on_measured_state" in by_name and "servo_on_link_encoder" in by_name:
        out.append(f"On the elastic plant, closing the position mode's QP on the measured link state (peak "
                   f"{m('position_qp_on_measured_state', 'peak_mm', 'position'):.0f} mm, residual "
                   f"{m('position_qp_on_measured_state', 'residual_mm', 'position'):.0f} mm) or the vendor servo on "
                   f"the link encoder (residual {m('servo_on_link_encoder', 'residual_mm', 'position'):.1f} mm, never "
                   "settling) rings or drifts: feedback of the link through the spring to the motor is non-collocated. "
                   "The vendor gains here are estimates made for a rigid plant.")
    if "cable_damping_50" in by_name:
        out.append(f"Stabilisation: a damping ratio of 0.5 in the cord brings position mode to "
                   f"{m('cable_damping_50', 'stabilisation_s', 'position'):.2f} s but leaves torque mode at "
                   f"{m('cable_damping_50', 'stabilisation_s', 'torque'):.2f} s (the swinging mass and the relative "
                   "band, see above).")
        better = [n for n, st in by_name.items() if st["stabilisation_s"]["torque_better"]]
        out.append("Torque mode stabilises faster only in: " + (", ".join(sorted(better)) if better else "none") +
                   " (with the observer alone its peak is large, so its 5 % band is wide).")
    return " ".join(out)


def dynamic_section(rep, out):
    d = f"{out}/dynamic_tracking"
    rep.h(2, "4. Dynamic trajectory tracking")
    rep.p("The demo's dynamic scenario (z = z0 + 0.1 sin(3 t) m; y a triangle at 0.1 m/s between -0.40 and +0.05 m "
          "with sharp corners: the reference velocity jumps), null-space compliance, with four low-level loops. "
          "Errors: position = task target - plant end effector, velocity = the target's reference velocity - plant "
          "end-effector velocity (J q_dot from the plant's true joint velocities: no numerical derivative), RMS over "
          "the run after a 0.5 s transient.")
    summary = read_rows(f"{d}/torque_tracking_summary.csv") if os.path.exists(f"{d}/torque_tracking_summary.csv") else []
    rows = [[LOOP_NAMES.get(r["loop"], r["loop"]), f"{float(r['ee_y_rms_mm']):.3f}", f"{float(r['ee_z_rms_mm']):.3f}",
             f"{float(r['ee_vy_rms_mm_s']):.2f}", f"{float(r['ee_vz_rms_mm_s']):.2f}", f"{float(r['rms_Nm']):.3f}"]
            for r in summary]
    rep.table(md_table(["loop", "y RMS [mm]", "z RMS [mm]", "v_y RMS [mm/s]", "v_z RMS [mm/s]", "torque RMS [N.m]"], rows))
    rep.p("Paper (Fig. dynamic-comparison, no numbers): custom torque control about as precise as position control; "
          "much more precise than Kinova's torque loop. Differences: the paper's position mode integrates its QP state "
          "open loop into the vendor servo; here the QP runs on the measured state (the open-loop variant, "
          "controller.position_mode_open_loop, is what the drop test uses); the joints are rigid here, so position "
          "control tracks with the vendor servo's full stiffness.")
    draw_dynamic(d, f"{d}/dynamic_tracking.png")
    rep.figure(f"{d}/dynamic_tracking.png", "Dynamic tracking: y and z position and velocity errors per loop")


def draw_dynamic(d, output):
    loops = [l for l in LOOP_NAMES if os.path.exists(f"{d}/torque_tracking_dynamic_{l}.csv")]
    if not loops:
        return
    fig, axes = plt.subplots(2, 2, figsize=(11, 6.5), sharex=True)
    columns = [("ee_err_y_mm", "y error [mm]"), ("ee_err_z_mm", "z error [mm]"), ("ee_verr_y_mm_s", "v_y error [mm/s]"),
               ("ee_verr_z_mm_s", "v_z error [mm/s]")]
    for loop in loops:
        rows = read_rows(f"{d}/torque_tracking_dynamic_{loop}.csv")[::5]
        t = np.array([float(r["t_s"]) for r in rows])
        for ax, (col, label) in zip(axes.flat, columns):
            ax.plot(t, [float(r[col]) for r in rows], linewidth=0.7, label=LOOP_NAMES[loop])
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("time since the switch [s]")
    axes[0, 0].legend(fontsize=8)
    save_figure(fig, output, 110, "Dynamic tracking errors (paper Fig. dynamic-comparison)", 11)


def dual_section(rep, out):
    d = f"{out}/dual_compliance"
    rep.h(2, "5. Dual compliance")
    rep.p("Dual compliance with the custom loop: a hand (a half-sine force on the tool, 12 N peak over 1.5 s) guides the end "
          "effector sideways, then down, and lets go. Metrics per guide: trigger in/out times (Schmitt trigger on the "
          "F/T wrench norm, 8 up / 4 down as in the paper's Fig. dual-compliance), peak wrench norm, how far the end "
          "effector moved while touched, and its drift in the 2 s after the release (the pose at release becomes the "
          "target, so ideally 0).")
    path = f"{d}/dual_compliance.md"
    if os.path.exists(path):
        with open(path) as f:
            text = f.read()
        rep.table("\n".join(l for l in text.splitlines() if l.startswith("|")))
    rep.p("Paper: thresholds 8 and 4 on the wrench norm, low forces to move the end effector, no numbers for drift. "
          "The hand here is a scripted force, not a person: it does not follow the arm.")
    draw_dual(d, f"{d}/dual_compliance.png")
    rep.figure(f"{d}/dual_compliance.png", "Dual compliance time series (paper Fig. dual-compliance), touched shaded")


def draw_dual(d, output):
    if not os.path.exists(f"{d}/dual_compliance.csv"):
        return
    rows = read_rows(f"{d}/dual_compliance.csv")
    t = np.array([float(r["t_s"]) for r in rows])
    touched = np.array([int(r["touched"]) for r in rows])
    panels = [("ee_force_N", "EE force norm [N]"), ("tau_norm_Nm", "joint torque norm [N.m]"),
              ("ee_speed_m_s", "EE speed [m/s]"), ("qd_norm_rad_s", "joint speed norm [rad/s]"),
              ("wrench_norm", "wrench norm (trigger)")]
    fig, axes = plt.subplots(len(panels), 1, figsize=(10, 9), sharex=True)
    for ax, (col, label) in zip(axes, panels):
        ax.plot(t, [float(r[col]) for r in rows], linewidth=0.8)
        ax.fill_between(t, 0, 1, where=touched > 0, color="0.85", transform=ax.get_xaxis_transform())
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1].axhline(8.0, linestyle="--", color="tab:blue")
    axes[-1].axhline(4.0, linestyle="--", color="tab:orange")
    axes[-1].set_xlabel("time [s]")
    save_figure(fig, output, 110, "Dual compliance", 11)


def main(argv):
    if len(argv) != 4:
        print(__doc__)
        return 2
    out, mode, seconds = argv[1], argv[2], float(argv[3])
    rep = Report(out)
    rep.h(1, "phri evaluation: the paper's five evaluations on the simulated Gen3")
    rep.p(f"Protocol: {'QUICK (shortened protocols: a smoke test, not the paper numbers)' if mode == 'quick' else 'full'}; "
          f"experiments took {seconds:.1f} s of wall time. Reproduce: phri evaluate --out {out}"
          f"{' --quick' if mode == 'quick' else ''}. Plant: MuJoCo Gen3 with drive friction, rotor inertia, sensor "
          "noise, 5 % link and drive-gain mismatch; rigid joints except in the drop test, which enables the plant's joint "
          "elasticity (plant.elasticity).")
    friction_section(rep, out)
    torque_tracking_section(rep, out)
    drop_section(rep, out)
    dynamic_section(rep, out)
    dual_section(rep, out)
    with open(f"{out}/report.md", "w") as f:
        f.write(rep.markdown())
    with open(f"{out}/report.html", "w") as f:
        f.write(rep.html())
    print(f"report: {out}/report.md, {out}/report.html")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
