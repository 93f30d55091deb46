"""ctest `report_ringing_measured_against_the_computed_mode` (tools/report/ringing.py).

A synthetic static torque-tracking log: white sensor noise (0.05 N.m, the plant's) on every joint and a
sine of known frequency and amplitude on one. The measurement must find that joint, frequency (within
0.3 Hz) and amplitude (within 10 %); the sentence must call it the joint's elastic mode when a computed
mode is within 10 %, say the open-loop figure does not explain it when none is, and report no ringing
when the log is noise alone. A one-off step (a joint slipping once) is not a ringing. The drop test's
late oscillation (evaluation_report.late_oscillation_sentence): synthetic traces swinging at 0.93 Hz
(torque) and bouncing at 6.4 Hz (position) are named as the pendulum and the bounce computed for the rig.

Usage: test_ringing.py TOOLS_REPORT_DIR
"""
import os
import sys
import tempfile

import numpy as np


def synthetic_rows(ring_joint, hz, amplitude, seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 10.0, 1e-3)
    rows = []
    errors = {j: 0.05 * rng.standard_normal(t.size) for j in range(1, 8)}
    if ring_joint:
        errors[ring_joint] += amplitude * np.sin(2 * np.pi * hz * t + 0.4)
    for k, tk in enumerate(t):
        row = {"t_s": f"{tk:.3f}", "error_norm_Nm": "0"}
        row.update({f"error_{j}_Nm": f"{errors[j][k]:.5f}" for j in range(1, 8)})
        rows.append(row)
    return rows


def modes(joint_hz):
    return [{"joint": str(j), "mode_hz": str(joint_hz.get(j, 200.0 + j)), "locked_link_hz": "100"} for j in range(1, 8)]


def main(argv):
    sys.path.insert(0, argv[1])
    from ringing import measure_ringing, ringing_sentence
    failures = []
    ring = measure_ringing(synthetic_rows(3, 49.3, 0.2))
    top = max(ring, key=lambda r: r["peak_amplitude_Nm"])
    if top["joint"] != 3 or abs(top["peak_hz"] - 49.3) > 0.3 or abs(top["peak_amplitude_Nm"] - 0.2) > 0.02:
        failures.append(f"ringing of joint 3 at 49.3 Hz, 0.2 N.m measured as {top}")
    explained = ringing_sentence("custom", ring, modes({3: 50.5}))
    if "the ringing is joint 3's elastic mode" not in explained:
        failures.append(f"a mode within 10 % not named: {explained}")
    unexplained = ringing_sentence("custom", ring, modes({3: 80.0}))
    if "does not explain it" not in unexplained or "(measured / computed 0.62)" not in unexplained:
        failures.append(f"a mode 38 % off called an explanation: {unexplained}")
    quiet = ringing_sentence("custom", measure_ringing(synthetic_rows(None, 0.0, 0.0)), modes({}))
    if "no ringing above" not in quiet:
        failures.append(f"noise alone called a ringing: {quiet}")
    step = synthetic_rows(None, 0.0, 0.0)
    for k, row in enumerate(step):
        if k >= 4000:
            row["error_2_Nm"] = f"{float(row['error_2_Nm']) + 1.1:.5f}"
    stepped = ringing_sentence("Kinova HV", measure_ringing(step), modes({}))
    if "no ringing above" not in stepped:
        failures.append(f"a one-off step called a ringing: {stepped}")
    failures += late_oscillation_failures()
    for f in failures:
        print("FAIL:", f)
    print(explained, unexplained, quiet, sep="\n")
    print(f"ringing checked: {len(failures)} failures")
    return 1 if failures else 0


def late_oscillation_failures():
    from evaluation_report import late_oscillation_sentence
    rng = np.random.default_rng(5)
    t = np.arange(0.0, 6.0, 0.002)
    cols = {}
    for i in range(5):
        cols[f"torque_{i}"] = 0.5 * np.sin(2 * np.pi * 0.93 * t + i) + 0.01 * rng.standard_normal(t.size)
        cols[f"position_{i}"] = 0.05 * np.sin(2 * np.pi * 6.4 * t + i) + 0.01 * rng.standard_normal(t.size)
    with tempfile.TemporaryDirectory() as d:
        with open(os.path.join(d, "drop_test_traces.csv"), "w") as f:
            f.write("t_s," + ",".join(cols) + "\n")
            for k, tk in enumerate(t):
                f.write(f"{tk:.3f}," + ",".join(f"{c[k]:.5f}" for c in cols.values()) + "\n")
        text = late_oscillation_sentence(d, {"pendulum": 0.93, "length_m": 0.29, "bounce": 6.37}, 0.25)
    failures = []
    if "torque mode 0.9" not in text or "above the 0.25 mm band): the weight's pendulum" not in text:
        failures.append(f"a 0.93 Hz swing of 0.5 mm not named the pendulum above the band: {text}")
    if "within the 0.25 mm band): its bounce on the cable" not in text:
        failures.append(f"a 6.4 Hz bounce of 0.05 mm not named the bounce within the band: {text}")
    print(text)
    return failures


if __name__ == "__main__":
    sys.exit(main(sys.argv))
