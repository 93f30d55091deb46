"""The package as users meet it: docstrings, type stubs for editors, and the installed copy."""
import ast
import inspect
import os
import pathlib
import subprocess
import sys

import pytest

import phri
from conftest import program

PACKAGE_DIR = pathlib.Path(phri.__file__).parent


def public_names():
    return [name for name in vars(phri) if not name.startswith("_") and name not in ("Optional", "Union")]


def test_every_public_class_function_and_method_has_a_docstring():
    missing = []
    for name in public_names():
        value = getattr(phri, name)
        if not (inspect.isclass(value) or callable(value)):
            continue
        doc = inspect.getdoc(value) or ""
        lines = [l for l in doc.splitlines() if l.strip() and not l.startswith(name + "(")]
        if not lines:
            missing.append(name)
        if inspect.isclass(value) and not issubclass(value, BaseException):
            for member, attribute in vars(value).items():
                if member.startswith("_") or isinstance(attribute, (property, type)) or not callable(attribute):
                    continue
                text = (attribute.__doc__ or "").strip().splitlines()
                if len([l for l in text if l.strip() and "(" not in l.split(" ")[0]]) == 0 and len(text) <= 1:
                    missing.append(f"{name}.{member}")
    assert not missing, f"no docstring: {missing}"


def test_stubs_describe_every_public_name_and_parse():
    stub = PACKAGE_DIR / "__init__.pyi"
    tree = ast.parse(stub.read_text())
    declared = {node.name for node in tree.body if isinstance(node, (ast.ClassDef, ast.FunctionDef))}
    declared |= {node.target.id for node in tree.body if isinstance(node, ast.AnnAssign)}
    assert (PACKAGE_DIR / "py.typed").exists()
    undeclared = [n for n in public_names() if n not in declared and not inspect.ismodule(getattr(phri, n))]
    assert not undeclared, f"not in the stubs: {undeclared}"
    text = stub.read_text()
    assert "def crba(model: Model, data: Data, q: numpy.typing.NDArray[numpy.float64]) -> numpy.typing.NDArray[numpy.float64]" in text
    signatures = [line for line in text.splitlines() if line.lstrip().startswith("def ")]
    assert len(signatures) > 200 and not [line for line in signatures if "::" in line]  # no C++ type left


def test_cmake_install_puts_a_working_package_where_debian_python_finds_it(tmp_path):
    build = os.environ.get("PHRI_BINARY_DIR") or pytest.skip("PHRI_BINARY_DIR is not set: run through ctest")
    prefix = tmp_path / "prefix"
    subprocess.run(["cmake", "--install", build, "--prefix", str(prefix)], check=True, capture_output=True)
    site = prefix / os.environ["PHRI_PYTHON_INSTALL_DIR"]
    for name in ("__init__.py", "__init__.pyi", "py.typed", "_paths.py"):
        assert (site / "phri" / name).exists(), name
    script = ("import phri, numpy; m = phri.Model.from_urdf_file(phri.locate('robots/kinova_gen3/gen3.urdf')); "
              "print(phri.__file__); print(phri.data_dir()); print(phri.crba(m, phri.Data(m), numpy.zeros(7))[0, 0])")
    environment = {**os.environ, "PYTHONPATH": str(site)}
    environment.pop("PHRI_DATA_DIR", None)
    done = subprocess.run([sys.executable, "-c", script], env=environment, capture_output=True, text=True,
                          cwd=tmp_path, check=True)
    module_file, data_dir, m00 = done.stdout.split()
    assert module_file.startswith(str(site)) and pathlib.Path(data_dir).resolve() == (prefix / "share/phri").resolve()
    assert float(m00) > 0.0
    # With the default prefix (/usr/local) that folder is on Debian's python3 path.
    default = pathlib.Path("/usr/local") / os.environ["PHRI_PYTHON_INSTALL_DIR"]
    assert str(default) in subprocess.run(["/usr/bin/python3", "-c", "import sys; print(sys.path)"],
                                          capture_output=True, text=True, check=True).stdout


TYPED_USE = """
import numpy as np
import numpy.typing as npt
import phri

model = phri.Model.from_urdf_file(phri.locate("robots/kinova_gen3/gen3.urdf"))
data = phri.Data(model)
M: npt.NDArray[np.float64] = phri.crba(model, data, np.zeros(model.nq))
config = phri.SimRobotConfig.from_yaml_file(phri.locate("configs/plant_gen3.yaml"))
config.drop_test.enabled = True
robot = phri.SimRobot(config)
loop = phri.ClosedLoop(robot, phri.Controller(phri.ControllerSettings()))
targets = phri.ControllerTargets(7)
targets.compliance_mode = phri.ComplianceMode.dual
targets.set_posture(np.zeros(7))
status: phri.CycleStatus = loop.step(targets)
ran: int = loop.run(5)
rows = loop.record(10)
result: phri.RunResult = phri.run("configs/demo.yaml", duration_s=1.0)
try:
    phri.Model.from_urdf_file("missing.urdf")
except phri.ConfigError as error:
    where: str = error.file
"""


def test_stubs_type_check_a_script_and_the_example_with_mypy(tmp_path):
    pytest.importorskip("mypy", reason="python3-mypy is not installed (scripts/setup installs it)")
    script = tmp_path / "typed_use.py"
    script.write_text(TYPED_USE)
    example = pathlib.Path(os.environ.get("PHRI_SOURCE_DIR", PACKAGE_DIR.parents[2])) / "examples/python/drops.py"
    done = subprocess.run([sys.executable, "-m", "mypy", "--strict", "--no-incremental", "--ignore-missing-imports",
                           "--cache-dir", str(tmp_path / "mypy_cache"), str(script), str(example)],
                          env={**os.environ, "MYPYPATH": str(PACKAGE_DIR.parent)}, capture_output=True, text=True,
                          cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
