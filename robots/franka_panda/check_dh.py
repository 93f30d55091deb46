#!/usr/bin/env python3
"""Independent check of robots/franka_panda/panda.urdf: forward kinematics of the flange (panda_link8) from phri's
Model against Franka's published modified (Craig) Denavit-Hartenberg table, and the URDF's masses against Franka's
inertials files.

DH table: https://github.com/frankaemika/docs source/control_parameters.rst, "Denavit-Hartenberg parameters"
(frankaemika.github.io/docs/control_parameters.html; commit 1da6bd33e741fbbffafa96e07c6c5cd4b0921055, where the
table is captioned "Franka Research 3"; at commit 321d1f13ddf37eb99943497d84905f0fc24afd5b the same numbers are
captioned "Panda's kinematic chain"). Craig's convention: iT(i-1) = RotX(alpha) TransX(a) RotZ(theta) TransZ(d).

  PYTHONPATH=build/release/python python3 robots/franka_panda/check_dh.py
"""
import math
import os
import sys

import numpy as np

import phri

HERE = os.path.dirname(os.path.abspath(__file__))

#            a        d      alpha
DH = [(0.0,     0.333,  0.0),
      (0.0,     0.0,   -math.pi / 2),
      (0.0,     0.316,  math.pi / 2),
      (0.0825,  0.0,    math.pi / 2),
      (-0.0825, 0.384, -math.pi / 2),
      (0.0,     0.0,    math.pi / 2),
      (0.088,   0.0,    math.pi / 2)]
FLANGE = (0.0, 0.107, 0.0)  # theta = 0

# Franka's masses [kg]: franka_description robots/fer/inertials.yaml (link0..link7) and
# end_effectors/franka_hand/inertials.yaml (hand, two fingers), commit b299b39d9692bfae795184df32a98ce7778d56af.
MASS_ARM = [2.3966, 2.7907, 2.5420, 2.2513, 2.2037, 2.2855, 1.353, 0.35973]
MASS_HAND = [0.6544, 0.0291, 0.0291]


def craig(a, d, alpha, theta):
    ca, sa, ct, st = math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta)
    return np.array([[ct, -st, 0.0, a],
                     [st * ca, ct * ca, -sa, -d * sa],
                     [st * sa, ct * sa, ca, d * ca],
                     [0.0, 0.0, 0.0, 1.0]])


def dh_flange(q):
    T = np.eye(4)
    for (a, d, alpha), theta in zip(DH, q):
        T = T @ craig(a, d, alpha, theta)
    return T @ craig(FLANGE[0], FLANGE[1], FLANGE[2], 0.0)


def rotation_error(R1, R2):
    """Angle of R1^T R2 [rad], from its skew part (atan2 of sin and cos: exact near 0, where acos is not)."""
    E = R1.T @ R2
    s = 0.5 * np.linalg.norm([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]])
    c = (np.trace(E) - 1.0) / 2.0
    return math.atan2(s, c)


def main():
    options = phri.ModelOptions()
    options.base_link = "panda_link0"
    options.tip_link = "panda_link8"
    options.locked_joints = ["panda_finger_joint1", "panda_finger_joint2"]
    model = phri.Model.from_urdf_file(os.path.join(HERE, "panda.urdf"), options)
    data = phri.Data(model)
    flange = model.frame_id("panda_link8")
    lo, hi = np.asarray(model.lower_limits), np.asarray(model.upper_limits)

    rng = np.random.default_rng(20240605)
    qs = [np.zeros(7), np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])]
    qs += [rng.uniform(lo, hi) for _ in range(10)]
    max_p = max_r = 0.0
    for q in qs:
        phri.forward_kinematics(model, data, q)
        phri.update_frame_placements(model, data)
        T = np.array(data.frame_placement(flange))
        D = dh_flange(q)
        max_p = max(max_p, float(np.linalg.norm(T[:3, 3] - D[:3, 3])))
        max_r = max(max_r, rotation_error(T[:3, :3], D[:3, :3]))
    print(f"flange FK vs Franka's DH table, {len(qs)} joint vectors (zero, ready pose, 10 random within the limits):")
    print(f"  max position error    {max_p:.3e} m")
    print(f"  max orientation error {max_r:.3e} rad")

    moving = sum(MASS_ARM[1:]) + sum(MASS_HAND)
    print(f"moving mass: phri Model {model.total_mass():.6f} kg, Franka's files (link1..link7 + hand + fingers) "
          f"{moving:.6f} kg, difference {model.total_mass() - moving:.2e} kg")
    print(f"  with link0 (fixed base, {MASS_ARM[0]} kg): {moving + MASS_ARM[0]:.5f} kg")
    ok = max_p < 1e-9 and max_r < 1e-9 and abs(model.total_mass() - moving) < 1e-9
    print("OK" if ok else "MISMATCH")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
