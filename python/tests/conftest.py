"""Shared pieces of the Python tests (run by ctest through run_pytest.py, which sets the environment:
PYTHONPATH to the build tree's package, PHRI_CLI, PHRI_REFERENCE, PHRI_LOOP_REFERENCE...)."""
import os
import pathlib

import pytest

import phri

SOURCE_DIR = pathlib.Path(os.environ.get("PHRI_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
GEN3_URDF = str(SOURCE_DIR / "robots/kinova_gen3/gen3.urdf")
PLANT_YAML = str(SOURCE_DIR / "configs/plant_gen3.yaml")
DEMO_YAML = str(SOURCE_DIR / "configs/demo.yaml")
PAPER_POSTURE = [0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57]


def program(variable):
    """A program the build made, named by the environment (skips when run outside ctest)."""
    path = os.environ.get(variable)
    if not path:
        pytest.skip(f"{variable} is not set: run the Python tests through ctest")
    return path


def plant_config(**changes):
    """The shipped plant at the paper demo's posture, with attribute changes."""
    config = phri.SimRobotConfig.from_yaml_file(PLANT_YAML)
    config.initial_q_rad = PAPER_POSTURE
    for name, value in changes.items():
        setattr(config, name, value)
    return config


def controller_settings(mode=None, loop=None):
    settings = phri.ControllerSettings()
    if mode is not None:
        settings.initial_compliance = mode
    if loop is not None:
        settings.initial_loop = loop
    return settings


@pytest.fixture
def gen3():
    model = phri.Model.from_urdf_file(GEN3_URDF)
    return model, phri.Data(model)


@pytest.fixture
def rig():
    """A simulated Gen3 and its controller, closed in a loop (null-space compliance, custom loop)."""
    robot = phri.SimRobot(plant_config())
    controller = phri.Controller(controller_settings())
    return robot, controller, phri.ClosedLoop(robot, controller)
