#!/usr/bin/env python3
"""Independent check of robots/ur5e/ur5e.urdf against UR's published DH parameters for the UR5e.

Run:  PYTHONPATH=build/release/python /usr/bin/python3 robots/ur5e/check_dh.py     (from /work/main)

UR's DH parameters (standard DH: T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)), from UR's page "Parameters for
calculations of kinematics and dynamics" (universal-robots.com, FAQ 45257; the same numbers as
config/ur5e/default_kinematics.yaml of UniversalRobots/Universal_Robots_ROS2_Description, which was generated from
them), together with UR's link masses and centres of mass in the DH link frames (same page):

    joint  a [m]     d [m]    alpha      link mass [kg]  COM in DH frame i [m]
    1      0         0.1625   pi/2       3.761           [0, -0.02561, 0.00193]
    2     -0.425     0        0          8.058           [0.2125, 0, 0.11336]
    3     -0.3922    0        0          2.846           [0.15, 0.0, 0.0265]
    4      0         0.1333   pi/2       1.37            [0, -0.0018, 0.01634]
    5      0         0.0997  -pi/2       1.3             [0, 0.0018, 0.01634]
    6      0         0.0996   0          0.365           [0, 0, -0.001159]

Frame conventions (fixed transforms, stated explicitly):
  * DH frame 0 is UR's controller 'Base' frame (x backwards). The URDF's base_link is REP-103 aligned (x forward):
    base_link -> base_link_inertia and base_link -> base are both Rz(pi) (ur_macro.xacro). Hence
    T(base_link -> X) = Rz(pi) * T_DH(0 -> X).
  * DH frame 6 is UR's tool flange frame (z out of the flange), which is ROS's tool0 (flange -> tool0 in
    ur_macro.xacro). So T(base_link -> tool0) = Rz(pi) * T_DH(0 -> 6), no tool-side correction.
  * The DH joint angles are the URDF's joint angles (no offsets: UR's zero is the stretched, horizontal arm).
The COM check is the link frames' check from inside: the DH-frame COMs land where the URDF's link inertials put them.

Expected error: not 1e-16 but ~1e-10, because default_kinematics.yaml writes pi/2 as 1.570796327 (2.05e-10 rad
too large) and carries -2.04e-11 m residuals in the wrist z offsets (UR's numbers, transcribed unchanged). The
script also builds the same URDF with those roundings replaced by exact values, and then the errors are ~1e-15.
"""
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
import phri

HERE = os.path.dirname(os.path.abspath(__file__))
URDF = os.path.join(HERE, "ur5e.urdf")

DH_A = [0.0, -0.425, -0.3922, 0.0, 0.0, 0.0]
DH_D = [0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996]
DH_ALPHA = [math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0]
UR_MASS = [3.761, 8.058, 2.846, 1.37, 1.3, 0.365]                      # UR's DH page = physical_parameters.yaml
UR_COM_DH = [[0, -0.02561, 0.00193], [0.2125, 0, 0.11336], [0.15, 0.0, 0.0265],
             [0, -0.0018, 0.01634], [0, 0.0018, 0.01634], [0, 0, -0.001159]]
UR_BASE_MASS = 4.0  # physical_parameters.yaml base_mass ("This mass might be incorrect"); not on the DH page


def rot_z(t):
    c, s = math.cos(t), math.sin(t)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


def dh(theta, d, a, alpha):
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct],
                     [st, ct * ca, -ct * sa, a * st],
                     [0.0, sa, ca, d],
                     [0.0, 0.0, 0.0, 1.0]])


def dh_frames(q):
    """base_link -> DH frame i, i = 1..6 (Rz(pi): base_link to UR's Base frame)."""
    T = rot_z(math.pi)
    out = []
    for i in range(6):
        T = T @ dh(q[i], DH_D[i], DH_A[i], DH_ALPHA[i])
        out.append(T.copy())
    return out


def rotation_angle(R):
    """The angle of R, accurate near 0 too (acos of the trace loses half the digits there)."""
    s = 0.5 * np.linalg.norm([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return math.atan2(s, (np.trace(R) - 1.0) / 2.0)


def check(model, samples, label):
    data = phri.Data(model)
    tool0 = model.frame_id("tool0")
    pos_err = ori_err = com_err = 0.0
    for q in samples:
        phri.forward_kinematics(model, data, q)
        phri.update_frame_placements(model, data)
        T_phri = np.array(data.frame_placement(tool0))
        frames = dh_frames(q)
        T_dh = frames[-1]
        pos_err = max(pos_err, np.linalg.norm(T_phri[:3, 3] - T_dh[:3, 3]))
        ori_err = max(ori_err, rotation_angle(T_phri[:3, :3].T @ T_dh[:3, :3]))
        for i in range(6):  # body i of the model: the link after joint i
            inertia = model.body_inertia(i)
            B = np.array(data.body_placement(i))
            com_phri = B[:3, :3] @ np.asarray(inertia.com).reshape(3) + B[:3, 3]
            com_dh = frames[i][:3, :3] @ np.array(UR_COM_DH[i], float) + frames[i][:3, 3]
            com_err = max(com_err, np.linalg.norm(com_phri - com_dh))
    print(f"{label}: tool0 vs DH over {len(samples)} joint vectors: max position error {pos_err:.3e} m, "
          f"max orientation error {ori_err:.3e} rad; link COMs vs UR's DH-frame COMs: max {com_err:.3e} m")
    return pos_err, ori_err, com_err


def main():
    rng = np.random.default_rng(5)
    model = phri.Model.from_urdf_file(URDF)
    lower, upper = np.asarray(model.lower_limits), np.asarray(model.upper_limits)
    samples = [np.zeros(6)] + [rng.uniform(lower, upper) for _ in range(10)]

    pos, ori, com = check(model, samples, "ur5e.urdf (UR's numbers as published)")

    # The same URDF with default_kinematics.yaml's roundings made exact: the residual above is theirs.
    with open(URDF) as f:
        text = f.read()
    exact = (text.replace('"1.570796327 ', '"1.5707963267948966 ')
                 .replace('"1.570796326589793 ', '"1.5707963267948966 ')
                 .replace("-2.044881182297852e-11", "0").replace("-2.042830148012698e-11", "0")
                 .replace("0.09959999999999999", "0.0996"))
    pos_x, ori_x, com_x = check(phri.Model.from_urdf_string(exact, source_name="ur5e.urdf, pi/2 exact"),
                                samples, "ur5e.urdf with pi/2 exact, wrist z residuals 0")

    # Masses: the model's moving mass vs UR's link masses; the base's from the URDF (fixed to the world, not in
    # the model's bodies) vs physical_parameters.yaml.
    moving = model.total_mass()
    urdf_masses = {l.get("name"): float(l.find("inertial/mass").get("value"))
                   for l in ET.parse(URDF).getroot().iter("link") if l.find("inertial") is not None}
    total_urdf = sum(urdf_masses.values())
    print(f"moving mass: model {moving:.6f} kg, UR's links {sum(UR_MASS):.6f} kg (diff {moving - sum(UR_MASS):.1e}); "
          f"per link: " + ", ".join(f"{model.body_inertia(i).mass:g}" for i in range(6)))
    print(f"total with the base: URDF {total_urdf:.6f} kg, physical_parameters.yaml {sum(UR_MASS) + UR_BASE_MASS:.6f} kg "
          f"(base_link_inertia {urdf_masses.get('base_link_inertia')} kg)")

    ok = pos < 1e-9 and ori < 1e-9 and com < 1e-9 and pos_x < 1e-12 and ori_x < 1e-12 and com_x < 1e-12 \
        and abs(moving - sum(UR_MASS)) < 1e-12 and abs(total_urdf - sum(UR_MASS) - UR_BASE_MASS) < 1e-12
    print("OK" if ok else "MISMATCH")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
