#!/usr/bin/env python3
"""What a closed loop costs from Python, against the same loop in C++, measured in one run.

    /usr/bin/python3 python/bench/bench_loop.py [--build build/release] [--seconds 10] [--repetitions 7]

The loop: the simulated Gen3 (plant_gen3.yaml, 5 % model mismatch, a push on the elbow and one on the
tool every 6 s) under the controller in dual compliance with the custom torque loop, `seconds` of
robot time at 1 kHz. Variants, each timed around the loop only, on a fresh robot and controller:

  cpp       phri_loop_reference: the loop written in C++ (read, step, write), a separate process
  py_step   Python calls ClosedLoop.step() once per cycle
  py_calls  Python calls robot.read(), controller.step(), robot.write() per cycle (three calls)
  py_run    Python calls ClosedLoop.run(n): the n cycles in C++, GIL released

Repetitions interleave the variants (in a rotating order), so a machine busy with something else
slows all of them alike; the script prints each variant's median and the ratio of medians to cpp.
Every run must end at the same joint positions as the C++ program, bit for bit (same loop), or
the script says so and exits with 1.
"""
import argparse
import pathlib
import statistics
import subprocess
import sys
import time

import numpy as np

PAPER_POSTURE = [0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57]


def scenario(phri, seconds):
    """The robot and controller of the benchmark (python/bench/closed_loop_reference.cpp builds the same)."""
    config = phri.SimRobotConfig.from_yaml_file(phri.locate("configs/plant_gen3.yaml"))
    config.initial_q_rad = PAPER_POSTURE
    config.mismatch.enabled = True
    pushes, start = [], 1.0
    while start < seconds:
        pushes.append(phri.ExternalForce("forearm_link", [0.0, 30.0, 0.0], start, 1.0, phri.ExternalForce.Profile.half_sine))
        pushes.append(phri.ExternalForce("tool", [0.0, -15.0, 0.0], start + 3.0, 1.0, phri.ExternalForce.Profile.half_sine))
        start += 6.0
    config.disturbances = pushes
    settings = phri.ControllerSettings()
    settings.initial_compliance = phri.ComplianceMode.dual
    return phri.SimRobot(config), phri.Controller(settings)


def time_cpp(program, seconds):
    out = subprocess.run([str(program), "--seconds", str(seconds)], capture_output=True, text=True, check=True).stdout
    fields = dict(line.split(" ", 1) for line in out.splitlines())
    return float(fields["loop_s"]), np.array([float.fromhex(w) for w in fields["final_q"].split()])


def time_py_step(phri, seconds):
    robot, controller = scenario(phri, seconds)
    loop = phri.ClosedLoop(robot, controller)
    step = loop.step
    cycles = round(seconds / robot.period_s)
    start = time.perf_counter()
    for _ in range(cycles):
        step()
    elapsed = time.perf_counter() - start
    return elapsed, robot.state().q_rad.copy()


def time_py_calls(phri, seconds):
    robot, controller = scenario(phri, seconds)
    command, targets = phri.RobotCommand(robot.dof), phri.ControllerTargets(robot.dof)
    read, step, write = robot.read, controller.step, robot.write
    ok, refused = phri.WriteStatus.ok, phri.SafetyFault.write_refused
    cycles = round(seconds / robot.period_s)
    start = time.perf_counter()
    for _ in range(cycles):
        state = read()
        step(state, targets, command)
        if write(command) != ok:
            controller.report_fault(refused, state.time_s)
    elapsed = time.perf_counter() - start
    return elapsed, robot.state().q_rad.copy()


def time_py_run(phri, seconds):
    robot, controller = scenario(phri, seconds)
    loop = phri.ClosedLoop(robot, controller)
    cycles = round(seconds / robot.period_s)
    start = time.perf_counter()
    loop.run(cycles)
    elapsed = time.perf_counter() - start
    return elapsed, robot.state().q_rad.copy()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", default="build/release", help="the CMake build folder (default: build/release)")
    parser.add_argument("--seconds", type=float, default=10.0, help="robot time of one loop (default: 10)")
    parser.add_argument("--repetitions", type=int, default=7, help="runs of each variant (default: 7)")
    args = parser.parse_args()
    build = pathlib.Path(args.build).resolve()
    sys.path.insert(0, str(build / "python"))
    import phri

    program = build / "python" / "phri_loop_reference"
    variants = {
        "cpp": lambda: time_cpp(program, args.seconds),
        "py_step": lambda: time_py_step(phri, args.seconds),
        "py_calls": lambda: time_py_calls(phri, args.seconds),
        "py_run": lambda: time_py_run(phri, args.seconds),
    }
    names = list(variants)
    times = {name: [] for name in names}
    finals = {}
    print(f"closed loop, {args.seconds:g} s of robot time ({round(args.seconds * 1000)} cycles), "
          f"{args.repetitions} repetitions, phri {phri.__version__}")
    for r in range(args.repetitions):
        for name in names[r % len(names):] + names[:r % len(names)]:
            elapsed, final_q = variants[name]()
            times[name].append(elapsed)
            finals.setdefault(name, final_q)
            if not np.array_equal(final_q, finals["cpp"] if "cpp" in finals else final_q):
                print(f"bench_loop: {name} ended elsewhere than the C++ loop: not the same loop", file=sys.stderr)
                return 1
        print(f"  repetition {r + 1}: " + ", ".join(f"{n} {times[n][-1]:.3f} s" for n in names))
    reference = statistics.median(times["cpp"])
    print(f"\n| variant | median s | min s | per cycle us | median / cpp median |")
    print("|---|---|---|---|---|")
    for name in names:
        median = statistics.median(times[name])
        print(f"| {name} | {median:.3f} | {min(times[name]):.3f} | {1e6 * median / (args.seconds * 1000):.1f} | "
              f"{median / reference:.3f} |")
    step_ratio = statistics.median(times["py_step"]) / reference
    run_ratio = statistics.median(times["py_run"]) / reference
    print(f"\nPython one call per cycle (py_step): {step_ratio:.3f} x C++ (target <= 1.3: "
          f"{'met' if step_ratio <= 1.3 else 'NOT met'})")
    print(f"Python calling a C++ run of N cycles (py_run): {run_ratio:.3f} x C++ (target <= 1.05: "
          f"{'met' if run_ratio <= 1.05 else 'NOT met'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
