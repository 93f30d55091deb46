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
SEGMENT_S = 1.0      # the spectrum's segments: 1 Hz bins; an oscillation must last through most of them (no source)


def dominant_frequency(signal, dt, min_hz=MIN_HZ, segment_s=SEGMENT_S):
    """(frequency [Hz], sine amplitude, peak / median of the spectrum) of the largest spectral peak
    above min_hz. A ringing is an oscillation that lasts: the spectrum is the median, bin by bin, of
    the power spectra of Hann-windowed segment_s segments (half overlapping, each mean removed), so that
    a one-off event (a joint slipping once, a step) that fills one segment's spectrum does not count.
    The amplitude sums the peak's main lobe (scalloping-free); the frequency interpolates the peak."""
    x = np.asarray(signal, dtype=float)
    n = min(len(x), max(8, int(round(segment_s / dt))))
    starts = range(0, len(x) - n + 1, max(1, n // 2))
    w = np.hanning(n)
    spectra = []
    for s0 in starts:
        seg = x[s0:s0 + n] - x[s0:s0 + n].mean()
        spectra.append((2.0 * np.abs(np.fft.rfft(seg * w)) / w.sum()) ** 2 / 2.0)  # a sine: A^2 / 2 at its bin
    power = np.median(np.array(spectra), axis=0)
    f = np.fft.rfftfreq(n, dt)
    band = f >= min_hz
    # A peak is a local maximum inside the band (not the edge of slower content rising below it).
    peak = band.copy()
    peak[1:-1] &= (power[1:-1] >= power[:-2]) & (power[1:-1] >= power[2:]) & band[:-2]
    peak[0] = peak[-1] = False
    if not peak.any():
        return float("nan"), float("nan"), float("nan")
    k = int(np.argmax(np.where(peak, power, -1.0)))
    # Parabolic interpolation of the peak on the log amplitude spectrum: finer than one bin.
    freq = f[k]
    amp = np.sqrt(power)
    if 0 < k < len(amp) - 1 and min(amp[k - 1:k + 2]) > 0:
        a, b, c = np.log(amp[k - 1:k + 2])
        denom = a - 2 * b + c
        if denom != 0:
            freq = f[k] + 0.5 * (a - c) / denom * (f[1] - f[0])
    # A sine's power spread over the Hann main lobe sums to (A^2 / 2) x 1.5 (the window's noise bandwidth).
    lobe = power[max(0, k - 2):k + 3].sum()
    amplitude = float(np.sqrt(2.0 * lobe / 1.5))
    floor = float(np.median(amp[band]))
    return float(freq), amplitude, float(amp[k] / floor) if floor > 0 else float("inf")


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
