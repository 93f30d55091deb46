#!/usr/bin/env python3
"""Self-test of tools/check_structure.py on trees made here: it must flag an upward include and a
function over the limit (counted with its initializer list, not fooled by braces in strings,
comments or lambdas), and pass a clean tree. Exit status 1 on any failed expectation."""
import importlib.util
import pathlib
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("check_structure", ROOT / "tools" / "check_structure.py")
check = importlib.util.module_from_spec(spec)
spec.loader.exec_module(check)

failures = []


def expect(condition, what):
    print(("ok   " if condition else "FAIL ") + what)
    if not condition:
        failures.append(what)


def tree(files):
    root = pathlib.Path(tempfile.mkdtemp())
    for name, text in files.items():
        path = root / "src" / "phri" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root


def body(lines):
    return "".join(f"  x += {i};\n" for i in range(lines))


clean = tree({
    "core/a.hpp": "#pragma once\nnamespace phri {\ninline int f() { return 1; }\n}\n",
    "control/b.cpp": '#include <phri/core/a.hpp>\n#include <phri/model/m.hpp>\nnamespace phri {\nint g() {\n'
                     + body(70) + '  const char* s = "}}}{{{";  // }\n  return 0;\n}\n}\n',
})
expect(check.main(["x", str(clean)]) == 0, "a clean tree passes")

upward = tree({"model/m.cpp": "#include <phri/control/controller.hpp>\nint h() { return 0; }\n"})
findings = check.layering_findings(upward / "src")
expect(len(findings) == 1 and "model" in findings[0] and "phri/control/" in findings[0], "an upward include is found")
expect(check.main(["x", str(upward)]) == 1, "an upward include fails the check")

nested = tree({"hardware/kortex_sdk/k.cpp": "#include <phri/control/controller.hpp>\nint s() { return 0; }\n"})
findings = check.layering_findings(nested / "src")
expect(len(findings) == 1 and "hardware" in findings[0] and "phri/control/" in findings[0],
       "a file in a module's subfolder is read, as part of that module")

config_on_sim = tree({"config/c.cpp": "#include <phri/sim/sim_robot.hpp>\nint c() { return 0; }\n"})
expect(len(check.layering_findings(config_on_sim / "src")) == 1, "the configuration library may not include the simulator")

unknown = tree({"gadgets/g.cpp": "int k() { return 0; }\n"})
expect(len(check.layering_findings(unknown / "src")) == 1, "a module outside the graph is found")

long_ctor = tree({"app/c.cpp": "namespace phri {\nC::C(int a)\n    : a_(a),\n      b_([&] { return a; }()),\n      c_{a} {\n"
                  + body(78) + "}\n}\n"})
found = check.length_findings(long_ctor / "src")
expect(len(found) == 1 and "83 lines" in found[0], "a constructor's initializer list counts toward its length")

lambdas = tree({"app/d.cpp": "namespace phri {\nvoid f() {\n  auto g = [](int x) {\n" + body(40)
                + "  };\n  struct S { int m() { return 0; } };\n" + body(40) + "}\n}\n"})
found = check.length_findings(lambdas / "src")
expect(len(found) == 1 and "85 lines" in found[0], "lambdas and local classes count as part of their function")

short = tree({"app/e.cpp": "namespace phri {\nint f() {\n" + body(77) + "  return 0;\n}\n}\n"})
expect(check.length_findings(short / "src") == [], "a function of exactly 80 lines passes")

python_in_library = tree({"sim/p.cpp": "#include <pybind11/pybind11.h>\nint p() { return 0; }\n"})
findings = check.layering_findings(python_in_library / "src")
expect(len(findings) == 1 and "pybind11/" in findings[0], "a library module including pybind11 is found")

long_binding = tree({"core/a.hpp": "#pragma once\n"})
(long_binding / "python" / "src").mkdir(parents=True)
(long_binding / "python" / "src" / "bind.cpp").write_text("void bind() {\n" + body(80) + "}\n")
expect(check.main(["x", str(long_binding)]) == 1, "a function over the limit in python/ fails the check")

sys.exit(1 if failures else 0)
