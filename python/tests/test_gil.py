"""Long C++ runs release the GIL: a Python thread keeps running Python code meanwhile.

The thread appends time stamps in a loop of pure Python. Holding the GIL, a C++ call would leave it no
chance to run until the call returned; with the GIL released it stamps all along. So the test counts
stamps strictly inside the call's time span and asks that they cover most of it.
"""
import threading
import time

import pytest

import phri
from conftest import controller_settings, plant_config


def stamps_during(call):
    stamps, running = [], threading.Event()
    running.set()

    def ticker():
        while running.is_set():
            stamps.append(time.perf_counter())
            for _ in range(200):  # a little pure-Python work between stamps
                pass

    thread = threading.Thread(target=ticker)
    thread.start()
    time.sleep(0.02)  # the ticker is running
    start = time.perf_counter()
    call()
    end = time.perf_counter()
    running.clear()
    thread.join()
    inside = [t for t in stamps if start < t < end]
    return inside, start, end


def assert_python_ran_throughout(inside, start, end):
    assert len(inside) > 100, f"only {len(inside)} stamps in {end - start:.3f} s"
    # No gap longer than a few switch intervals (5 ms each) while C++ ran: the GIL was free.
    gaps = [b - a for a, b in zip([start] + inside, inside + [end])]
    assert max(gaps) < 0.25 * (end - start), f"largest gap {max(gaps):.3f} s of {end - start:.3f} s"


def test_closed_loop_run_releases_the_gil():
    robot = phri.SimRobot(plant_config())
    loop = phri.ClosedLoop(robot, phri.Controller(controller_settings()))
    inside, start, end = stamps_during(lambda: loop.run(4000))
    assert end - start > 0.04
    assert_python_ran_throughout(inside, start, end)
    assert loop.cycles == 4000


def test_an_experiment_releases_the_gil():
    options = phri.TorqueTrackingOptions()
    options.output_dir = ""
    options.figure_script = ""
    options.scenarios = [phri.TrackingScenario.static]
    options.loops = [phri.LowLevelMode.custom]
    options.position_phase_s = 0.5
    options.static_duration_s = 1.0
    result = None

    def run():
        nonlocal result
        result = phri.run_torque_tracking(options, progress=False)

    inside, start, end = stamps_during(run)
    assert_python_ran_throughout(inside, start, end)
    assert len(result.runs) == 1 and result.runs[0].samples > 0
