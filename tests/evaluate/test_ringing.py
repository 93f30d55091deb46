"""ctest `report_ringing_measured_against_the_computed_mode` (tools/report/ringing.py).

A synthetic static torque-tracking log: white sensor noise (0.05 N.m, the plant's) on every joint and a
sine of known frequency and amplitude on one. The measurement must find that joint, frequency (within
0.3 Hz) and amplitude (within 10 %); the sentence must call it the joint's elastic mode when a computed
mode is within 10 %, say the open-loop figure does not explain it when none is, and report no ringing
when the log is noise alone.

Usage: test_ringing.py TOOLS_REPORT_DIR
"""
import sys

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
    for f in failures:
        print("FAIL:", f)
    print(explained, unexplained, quiet, sep="\n")
    print(f"ringing checked: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
