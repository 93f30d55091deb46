"""phri: control framework for physical human-robot interaction, from Python.

The C++ library (a Kinova Gen3 simulated in MuJoCo, a QP whole-body controller, low-level torque
loops) with numpy arrays in and out::

    import numpy as np, phri
    model = phri.Model.from_urdf_file(phri.locate("robots/kinova_gen3/gen3.urdf"))
    data = phri.Data(model)
    M = phri.crba(model, data, np.zeros(model.nq))      # a read-only view of data.mass_matrix

    robot = phri.SimRobot(phri.SimRobotConfig.from_yaml_file(phri.locate("configs/plant_gen3.yaml")))
    controller = phri.Controller(phri.ControllerSettings())   # the shipped Gen3 files
    loop = phri.ClosedLoop(robot, controller)
    loop.step()                      # one period: read, controller step, write
    rows = loop.record(1000)         # 1000 periods in C++ (GIL released), as a numpy structured array

    result = phri.run("configs/demo.yaml", duration_s=5, out_dir="out/py")   # like `phri run`
    log = phri.load_log(result.log_path)

Arrays that come out of phri are views of C++ buffers wherever the buffer outlives the call (state,
command, Data, controller outputs): they change with the next step; copy() what you keep. Errors are
phri.Error subclasses (ConfigError, IoError, ExperimentError, ArgumentError) carrying the C++ message.
"""
from __future__ import annotations

import dataclasses as _dataclasses
import os as _os
import pathlib as _pathlib
from typing import Optional, Union

from . import _paths
from . import _phri
from ._phri import *  # noqa: F401,F403 (the compiled API is the package's API)

__version__: str = _phri.version()

_phri._set_data_dir(_os.environ.get("PHRI_DATA_DIR", _paths.DATA_DIR))

# The compiled classes present themselves as phri.X (reprs, help()), the package users import.
for _value in vars(_phri).values():
    if isinstance(_value, type) and _value.__module__ == "phri._phri":
        _value.__module__ = "phri"


@_dataclasses.dataclass
class RunResult:
    """What phri.run returns: the run's summary and where its CSV log went."""

    summary: RunSummary
    log_path: str

    def log(self) -> numpy.typing.NDArray[Any]:
        """The run's log as a numpy structured array (phri.load_log)."""
        return load_log(self.log_path)


def run(config: Union[str, _os.PathLike[str]], duration_s: Optional[float] = None,
        out_dir: Union[str, _os.PathLike[str]] = "out",
        real_time: bool = False, status_line: bool = False, log: Optional[str] = None) -> RunResult:
    """Runs a session as `phri run --config CONFIG` does (simulated arm, FSM and its timeline, log), without the
    figure: lockstep unless real_time, for duration_s (default: the configuration's), the log written into out_dir.
    A relative `config` not found from the working directory is looked up in phri's data (phri.locate). The
    loop runs in C++ with the GIL released; phase lines go to sys.stdout. `log`: "csv" or "mcap" (default:
    the configuration's logging.format; auto: mcap for runs over 60 s)."""
    config = Config.from_yaml_file(locate(_os.fspath(config)))  # the shipped configs/ from anywhere
    if duration_s is not None:
        config.run.duration_s = float(duration_s)
    if log is not None:
        if log not in ("csv", "mcap"):
            raise ValueError(f"run: log is 'csv' or 'mcap', not {log!r}")
        config.log_format_auto = False
        config.logging.format = LogFormat.mcap if log == "mcap" else LogFormat.csv
    resolve_log_format(config)
    out = _pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    config.logging.path = str(out / _pathlib.Path(config.logging.path).name)  # edits config in place
    robot = SimRobot(config.plant)
    controller = Controller(config.controller)
    if config.body_regions is not None:
        config.logging.pfl_links = contact_links(controller)
    config.logging.joint_names = [j.name for j in controller.model.joints]
    config.logging.has_ft_sensor = config.plant.ft_sensor_present()
    fsm = Fsm(config.fsm, controller)
    logger = Logger(config.logging) if config.logging_enabled else None
    options = RunOptions()
    options.duration_s = config.run.duration_s
    options.real_time = real_time
    options.status_line = status_line
    options.phases = [PhaseMark(0.0, "startup")] + [PhaseMark(e.time_s, e.event.name) for e in config.fsm.timeline]
    summary = run_session(robot, controller, fsm, logger, options, config.body_regions)
    if logger is not None:
        logger.close()
    return RunResult(summary, config.logging.path if logger is not None else "")


# Only phri's names: the helpers of the annotations above are not part of the API.
del annotations, Optional, Union
