"""The ringing of a torque-tracking run, measured from its log and set beside the plant's computed
elastic modes (issue 39: "the ringing measured and explained by a computed figure").

measure_ringing(rows) takes the rows of torque_tracking_<scenario>_<loop>.csv and returns, per joint,
the dominant frequency of the measured torque error above MIN_HZ, its amplitude, the error's RMS and
the peak over the spectrum's median (the noise floor). ringing_sentence() states what this run's
numbers say against elastic_modes_<scenario>_<loop>.csv (src/phri/experiments/elastic_modes.hpp).
"""
import numpy as np

MIN_HZ = 5.0         # slower content is the posture's and friction's drift, not a ringing (no source)
MIN_PEAK_RATIO = 10  # a peak under 10x the noise floor is not called a ringing (no source)
MATCH = 0.10         # a measured peak within 10 % of a computed mode is called that mode (no source)


def dominant_frequency(signal, dt, min_hz=MIN_HZ):
    """(frequency [Hz], sine amplitude, peak / median of the spectrum) of the largest spectral peak
    above min_hz, Hann window, mean removed."""
    x = np.asarray(signal, dtype=float)
    x = x - x.mean()
    w = np.hanning(len(x))
    spectrum = 2.0 * np.abs(np.fft.rfft(x * w)) / w.sum()
    f = np.fft.rfftfreq(len(x), dt)
    band = f >= min_hz
    if not band.any():
        return float("nan"), float("nan"), float("nan")
    k = np.argmax(np.where(band, spectrum, -1.0))
    # Parabolic interpolation of the peak on the log spectrum: finer than one bin.
    freq = f[k]
    if 0 < k < len(spectrum) - 1 and min(spectrum[k - 1:k + 2]) > 0:
        a, b, c = np.log(spectrum[k - 1:k + 2])
        denom = a - 2 * b + c
        if denom != 0:
            freq = f[k] + 0.5 * (a - c) / denom * (f[1] - f[0])
    floor = float(np.median(spectrum[band]))
    return float(freq), float(spectrum[k]), float(spectrum[k] / floor) if floor > 0 else float("inf")


def measure_ringing(rows, transient_s=0.5):
    """Per joint (in column order error_1_Nm, error_2_Nm, ...): peak_hz, peak_amplitude_Nm, rms_Nm,
    peak_over_floor, over the rows from transient_s on."""
    t = np.array([float(r["t_s"]) for r in rows])
    keep = t >= transient_s
    dt = float(np.median(np.diff(t)))
    joints = sorted((c for c in rows[0] if c.startswith("error_") and c.endswith("_Nm") and c[6:-3].isdigit()),
                    key=lambda c: int(c[6:-3]))
    out = []
    for col in joints:
        e = np.array([float(r[col]) for r in rows])[keep]
        hz, amp, ratio = dominant_frequency(e, dt)
        out.append({"joint": int(col[6:-3]), "peak_hz": hz, "peak_amplitude_Nm": amp,
                    "rms_Nm": float(np.sqrt(np.mean((e - e.mean()) ** 2))), "peak_over_floor": ratio})
    return out


def ringing_sentence(loop, ring, modes):
    """What the run's numbers say: the strongest ringing against the computed modes, or none."""
    if not ring:
        return f"{loop} loop: no joint errors in the log."
    top = max(ring, key=lambda r: r["peak_amplitude_Nm"] if r["peak_over_floor"] >= MIN_PEAK_RATIO else -1.0)
    if top["peak_over_floor"] < MIN_PEAK_RATIO:
        best = max(ring, key=lambda r: r["peak_over_floor"])
        return (f"{loop} loop: no ringing above {MIN_PEAK_RATIO}x the noise floor on any joint (the largest peak is "
                f"{best['peak_over_floor']:.1f}x the floor, at {best['peak_hz']:.1f} Hz on joint {best['joint']}).")
    hz, j = top["peak_hz"], top["joint"]
    own = next((float(m["mode_hz"]) for m in modes if int(m["joint"]) == j), float("nan"))
    nearest = min(modes, key=lambda m: abs(float(m["mode_hz"]) - hz))
    near_hz = float(nearest["mode_hz"])
    ringing_joints = [r["joint"] for r in ring if r["peak_over_floor"] >= MIN_PEAK_RATIO and abs(r["peak_hz"] - hz) <= MATCH * hz]
    text = (f"{loop} loop: the strongest ringing is at {hz:.1f} Hz on joint {j} (amplitude {top['peak_amplitude_Nm']:.4f} "
            f"N.m, {top['peak_over_floor']:.0f}x the noise floor; joints ringing at that frequency: "
            f"{', '.join(str(x) for x in ringing_joints)}); joint {j}'s computed two-mass mode is {own:.1f} Hz "
            f"(measured / computed {hz / own:.2f}), the nearest computed mode is joint {nearest['joint']}'s {near_hz:.1f} Hz. ")
    if abs(hz / own - 1.0) <= MATCH:
        text += f"Within {100 * MATCH:.0f} %: the ringing is joint {j}'s elastic mode."
    elif abs(hz / near_hz - 1.0) <= MATCH:
        text += (f"Not joint {j}'s own mode; within {100 * MATCH:.0f} % of joint {nearest['joint']}'s computed mode (the "
                 "joints are coupled through the arm's inertia, which the per-joint figure leaves out).")
    else:
        text += (f"No computed open-loop mode within {100 * MATCH:.0f} %: the open-loop figure does not explain it; the "
                 "loop closed around the spring moves the mode (not computed here).")
    return text
