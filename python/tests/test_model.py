"""Model and algorithms from Python against the C++ library's own results, bit for bit.

phri_py_reference (python/tests/reference_dynamics.cpp) computes M(q), h(q, qd), g(q), RNEA and every
frame's Jacobian in the three reference frames with the same library, for inputs this test draws and
hands over as hexadecimal floats, and prints them as hexadecimal floats: nothing is lost either way,
so equality is exact equality. What it checks is the binding: argument conversion, row/column order,
which buffer a view shows, stale or shared buffers between calls.
"""
import subprocess

import numpy as np
import pytest

import phri
from conftest import GEN3_URDF, program


def reference_terms(model, cases):
    lines = "\n".join(" ".join(float(x).hex() for x in np.concatenate(case)) for case in cases) + "\n"
    out = subprocess.run([program("PHRI_REFERENCE"), GEN3_URDF], input=lines, capture_output=True, text=True, check=True)
    n = model.nv
    results, current = [], None
    for line in out.stdout.splitlines():
        words = line.split()
        if words[0] == "M":
            current = {"J": {}}
            results.append(current)
        numbers = words[3:] if words[0] == "J" else words[1:]
        values = np.array([float.fromhex(w) for w in numbers])
        if words[0] == "J":
            current["J"][(words[1], words[2])] = values.reshape(6, n)
        else:
            current[words[0]] = values.reshape(n, n) if words[0] == "M" else values
    return results


def draw_cases(model, count, seed):
    rng = np.random.default_rng(seed)
    lower = np.where(np.isfinite(model.lower_limits), model.lower_limits, -np.pi)
    upper = np.where(np.isfinite(model.upper_limits), model.upper_limits, np.pi)
    return [(rng.uniform(lower, upper), rng.uniform(-1.5, 1.5, model.nv), rng.uniform(-5, 5, model.nv)) for _ in range(count)]


def test_mass_matrix_bias_and_jacobians_equal_the_cpp_results_exactly(gen3):
    model, data = gen3
    cases = draw_cases(model, 6, seed=19)
    expected = reference_terms(model, cases)
    frames = {"world": phri.ReferenceFrame.world, "local_world_aligned": phri.ReferenceFrame.local_world_aligned,
              "local": phri.ReferenceFrame.local}
    assert len(expected) == len(cases)
    for (q, qd, qdd), ref in zip(cases, expected):
        assert np.array_equal(phri.crba(model, data, q), ref["M"])
        assert np.array_equal(phri.nonlinear_effects(model, data, q, qd), ref["h"])
        assert np.array_equal(phri.compute_gravity(model, data, q), ref["g"])
        assert np.array_equal(phri.rnea(model, data, q, qd, qdd), ref["tau"])
        phri.forward_kinematics(model, data, q)
        phri.update_frame_placements(model, data)
        assert len(ref["J"]) == 3 * model.num_frames
        for frame in model.frames:
            for name, rf in frames.items():
                J = phri.frame_jacobian(model, data, model.frame_id(frame.name), rf)
                assert np.array_equal(J, ref["J"][(frame.name, name)]), (frame.name, name)


def test_compute_all_terms_gives_the_same_terms_as_the_single_algorithms(gen3):
    model, data = gen3
    q, qd, _ = draw_cases(model, 1, seed=3)[0]
    M = phri.crba(model, data, q).copy()
    h = phri.nonlinear_effects(model, data, q, qd).copy()
    assert phri.compute_all_terms(model, data, q, qd)
    # The same M to rounding: crba sums each body's inertia 4-wide inside its composite pass, while
    # compute_all_terms reuses the inertias its Newton-Euler pass computes.
    assert np.allclose(data.mass_matrix, M, rtol=1e-14, atol=1e-14 * np.abs(M).max())
    assert np.array_equal(data.nonlinear_effects, h)
    # M is what numpy would factor: the solve in place agrees with numpy's to rounding.
    assert phri.compute_mass_matrix_cholesky(data)
    x = h.copy()
    phri.mass_matrix_solve_in_place(data, x)
    assert np.allclose(x, np.linalg.solve(M, h), rtol=1e-10, atol=1e-12)


def test_results_are_read_only_views_of_data_without_copies(gen3):
    model, data = gen3
    q = np.zeros(model.nq)
    M = phri.crba(model, data, q)
    assert np.shares_memory(M, data.mass_matrix) and not M.flags.writeable and M.base is not None
    with pytest.raises(ValueError):
        M[0, 0] = 1.0
    # A view sees the next computation: the same memory, new values.
    before = M[1, 1]
    phri.crba(model, data, np.full(model.nq, 0.7))
    assert M[1, 1] != before
    g = phri.compute_gravity(model, data, q)
    assert np.shares_memory(g, data.gravity_torque)
    placement = data.frame_placement(model.frame_id("end_effector_link"))
    assert placement.shape == (4, 4) and not placement.flags.writeable
    assert np.array_equal(placement[3], [0, 0, 0, 1])


def test_jacobian_fills_a_given_array_in_place(gen3):
    model, data = gen3
    phri.forward_kinematics(model, data, np.full(model.nq, 0.3))
    out = np.zeros((6, model.nv), order="F")
    returned = phri.frame_jacobian(model, data, model.frame_id("end_effector_link"), phri.ReferenceFrame.world, out)
    assert returned is out and np.any(out != 0.0)
    with pytest.raises(phri.ArgumentError, match="Fortran order"):
        phri.frame_jacobian(model, data, 0, phri.ReferenceFrame.world, np.zeros((6, model.nv)))  # C order
    with pytest.raises(phri.ArgumentError, match="index 99 out of range"):
        phri.frame_jacobian(model, data, 99, phri.ReferenceFrame.world)


def test_model_description(gen3):
    model, _ = gen3
    assert (model.nq, model.nv) == (7, 7)
    assert model.joints[0].name == "joint_1" and model.joints[1].has_position_limits()
    assert model.total_mass() == pytest.approx(sum(model.body_inertia(i).mass for i in range(model.num_bodies)))
    assert model.has_frame("end_effector_link") and not model.has_frame("nope")
