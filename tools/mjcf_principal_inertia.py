#!/usr/bin/python3
"""Rewrite every <inertial ... fullinertia="ixx iyy izz ixy ixz iyz"/> of an MJCF file as the
equivalent quat + diaginertia (principal frame), computed here with LAPACK in double precision.

Why: MuJoCo 2.2.2 diagonalises fullinertia with its own iterative 3x3 eigensolver, which leaves
errors of ~1e-10 kg.m^2 in the compiled tensor, more than the 1e-9 relative agreement we ask of
phri's dynamics against MuJoCo. Given quat + diaginertia, MuJoCo uses them as they are.
The original tensor is kept in a comment on the line above, so the file still shows the URDF numbers.

usage: tools/mjcf_principal_inertia.py robots/kinova_gen3/gen3_plant.xml   (edits in place)
"""
import re
import sys

import numpy as np


def principal(ixx, iyy, izz, ixy, ixz, iyz):
    tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    moments, axes = np.linalg.eigh(tensor)
    if np.linalg.det(axes) < 0:
        axes[:, 0] = -axes[:, 0]
    # rotation matrix -> quaternion (w, x, y, z)
    r = axes
    w = np.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2.0
    x = np.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2.0
    y = np.sqrt(max(0.0, 1.0 - r[0, 0] + r[1, 1] - r[2, 2])) / 2.0
    z = np.sqrt(max(0.0, 1.0 - r[0, 0] - r[1, 1] + r[2, 2])) / 2.0
    x = np.copysign(x, r[2, 1] - r[1, 2])
    y = np.copysign(y, r[0, 2] - r[2, 0])
    z = np.copysign(z, r[1, 0] - r[0, 1])
    q = np.array([w, x, y, z])
    q /= np.linalg.norm(q)
    rebuilt = r @ np.diag(moments) @ r.T
    assert np.abs(rebuilt - tensor).max() < 1e-15 * max(1.0, np.abs(tensor).max()) * 100
    return q, moments


def main(path):
    text = open(path).read()
    pattern = re.compile(r'(?P<indent>[ \t]*)<inertial(?P<before>[^>]*?)\s*fullinertia="(?P<t>[^"]+)"(?P<after>[^>]*)/>')

    def replace(match):
        values = [float(v) for v in match.group("t").split()]
        q, moments = principal(*values)
        indent = match.group("indent")
        fmt = lambda a: " ".join(repr(float(v)) for v in a)
        return (f'{indent}<!-- fullinertia (URDF tensor, MuJoCo order ixx iyy izz ixy ixz iyz): {match.group("t")} -->\n'
                f'{indent}<inertial{match.group("before")} quat="{fmt(q)}"\n'
                f'{indent}          diaginertia="{fmt(moments)}"{match.group("after")}/>')

    new_text, count = pattern.subn(replace, text)
    open(path, "w").write(new_text)
    print(f"{path}: {count} inertial(s) rewritten")


if __name__ == "__main__":
    main(sys.argv[1])
