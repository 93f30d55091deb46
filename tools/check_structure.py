#!/usr/bin/env python3
"""Checks the shape of src/phri (run by ctest as `structure`; exit status 1 on any finding).

1. Layering: a file of module M includes <phri/N/...> only for N == M or a module below M
   (MODULE_DEPENDENCIES, the same graph as the top-level CMakeLists.txt).
2. Function length: no function in src/, apps/ or python/ (the bindings) longer than
   MAX_FUNCTION_LINES, counted from the first line of its declaration (template and initializer
   list included) to its closing brace.
3. The library knows nothing of Python: no file of src/phri includes pybind11 or Python.h (the
   bindings live in python/, above every module).

    tools/check_structure.py [--layering-only] [ROOT]   (default ROOT: the folder above tools/)

The build runs it with --layering-only (CMakeLists.txt, target phri_layering), so an upward include
stops the build; ctest runs the whole check.
"""
import pathlib
import re
import sys

MAX_FUNCTION_LINES = 80

# Each module's direct dependencies (CMakeLists.txt, phri_add_module). Keep the two in step.
MODULE_DEPENDENCIES = {
    "core": [],
    "model": ["core"],
    "qp": ["core"],
    "robot": ["core"],
    "lowlevel": ["robot"],
    "safety": ["robot"],
    "control": ["model", "qp", "robot", "lowlevel", "safety"],
    "trajectory": ["control"],
    "config": ["control", "trajectory"],
    "sim": ["robot", "config"],
    "hardware": ["robot"],
    "app": ["config", "control", "trajectory", "sim"],
    "experiments": ["app", "control", "sim"],
    "dashboard": ["app"],
    "ros2": ["app"],
}

INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]phri/([A-Za-z0-9_]+)/', re.M)
PYTHON_INCLUDE = re.compile(r'^\s*#\s*include\s*[<"](pybind11/|Python\.h)', re.M)
SCOPE_KEYWORD = re.compile(r"\b(namespace|class|struct|enum|union)\b|^\s*extern\s*\"C\"")
FUNCTION_TAIL = re.compile(r"(\)|\}|\bconst|\bnoexcept|\boverride|\bfinal|\bmutable|->\s*[\w:<>,\s*&]+)\s*$")


def reachable(module):
    seen, stack = set(), [module]
    while stack:
        for dep in MODULE_DEPENDENCIES.get(stack.pop(), []):
            if dep not in seen:
                seen.add(dep)
                stack.append(dep)
    return seen


def layering_findings(src):
    findings = []
    for path in sorted(src.glob("phri/**/*")):
        if path.suffix not in (".hpp", ".cpp") or len(path.relative_to(src / "phri").parts) < 2:
            continue
        module = path.relative_to(src / "phri").parts[0]  # a file in a module's subfolder belongs to it
        if module not in MODULE_DEPENDENCIES:
            findings.append(f"{path}: module '{module}' is not in tools/check_structure.py's graph")
            continue
        allowed = reachable(module) | {module}
        text = path.read_text()
        for match in PYTHON_INCLUDE.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            findings.append(f"{path}:{line}: module '{module}' includes {match.group(1)}: Python belongs in python/")
        for match in INCLUDE.finditer(text):
            target = match.group(1)
            if target not in allowed:
                line = text.count("\n", 0, match.start()) + 1
                findings.append(f"{path}:{line}: module '{module}' includes phri/{target}/, which is not below it")
    return findings


def cmake_graph_findings(cmake_lists):
    """The module graph in CMakeLists.txt (phri_add_module) must be MODULE_DEPENDENCIES."""
    if not cmake_lists.is_file():
        return []
    graph = {}
    for match in re.finditer(r"phri_add_module\(\s*(\w+)([^)]*)\)", cmake_lists.read_text()):
        words = match.group(2).split()
        deps = words[words.index("DEPENDS") + 1:] if "DEPENDS" in words else []
        if "PRIVATE_DEPENDS" in deps:
            deps = deps[:deps.index("PRIVATE_DEPENDS")]
        graph[match.group(1)] = sorted(deps)
    expected = {module: sorted(deps) for module, deps in MODULE_DEPENDENCIES.items()}
    if graph != expected:
        return [f"{cmake_lists}: module graph {graph} differs from tools/check_structure.py's {expected}"]
    return []


def strip_comments_and_strings(text):
    """Same length and line structure as text, with comments, strings and chars blanked."""
    out = []
    i, n = 0, len(text)

    def blank(chunk):
        return "".join(c if c == "\n" else " " for c in chunk)

    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(blank(text[i:j]))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(blank(text[i:j]))
            i = j
        elif text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            open_paren = text.find("(", i)
            delimiter = text[i + 2:open_paren]
            j = text.find(")" + delimiter + '"', open_paren)
            j = n if j < 0 else j + len(delimiter) + 2
            out.append('""' + blank(text[i + 2:j]))
            i = j
        elif c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + blank(text[i + 1:j - 1]) + c)
            i = j
        elif c == "#" and (i == 0 or text[i - 1] == "\n"):  # preprocessor line (with continuations)
            j = i
            while True:
                j = text.find("\n", j)
                if j < 0 or text[j - 1] != "\\":
                    break
                j += 1
            j = n if j < 0 else j
            out.append(blank(text[i:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def matching_brace(code, open_index):
    depth = 0
    for k in range(open_index, len(code)):
        if code[k] == "{":
            depth += 1
        elif code[k] == "}":
            depth -= 1
            if depth == 0:
                return k
    return len(code) - 1


def function_lengths(code):
    """(first line, last line, signature) of every function body outside other function bodies."""
    functions = []
    statement_start = 0
    paren_depth = 0
    i = 0
    while i < len(code):
        c = code[i]
        if c in ";}":
            statement_start = i + 1
            paren_depth = 0
        elif c == "(":
            paren_depth += 1
        elif c == ")":
            paren_depth -= 1
        elif c == "{":
            statement = code[statement_start:i]
            if SCOPE_KEYWORD.search(statement) and "(" not in statement.split("{")[0].split("=")[0]:
                statement_start = i + 1  # namespace, class, struct or enum body: look inside
            elif paren_depth == 0 and FUNCTION_TAIL.search(statement) and "=" not in _outside_parens(statement):
                end = matching_brace(code, i)
                first = statement_start + len(statement) - len(statement.lstrip())
                functions.append((code.count("\n", 0, first) + 1, code.count("\n", 0, end) + 1,
                                  " ".join(statement.split())[:90]))
                i = end
                statement_start = end + 1
            else:
                i = matching_brace(code, i)  # a braced initializer inside the statement
        i += 1
    return functions


def _outside_parens(statement):
    depth, kept = 0, []
    for c in statement:
        if c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
        elif depth == 0:
            kept.append(c)
    return "".join(kept)


def length_findings(src):
    findings = []
    for path in sorted(src.rglob("*")):
        if path.suffix not in (".hpp", ".cpp"):
            continue
        code = strip_comments_and_strings(path.read_text())
        for first, last, signature in function_lengths(code):
            lines = last - first + 1
            if lines > MAX_FUNCTION_LINES:
                findings.append(f"{path}:{first}: {lines} lines (> {MAX_FUNCTION_LINES}): {signature}")
    return findings


def main(argv):
    layering_only = "--layering-only" in argv
    args = [a for a in argv[1:] if a != "--layering-only"]
    root = pathlib.Path(args[0]) if args else pathlib.Path(__file__).resolve().parent.parent
    src = root / "src"
    if not (src / "phri").is_dir():
        print(f"check_structure: {src}/phri is not a directory", file=sys.stderr)
        return 2
    findings = layering_findings(src)
    if (root / "CMakeLists.txt").is_file():
        findings += cmake_graph_findings(root / "CMakeLists.txt")
    if not layering_only:
        findings += length_findings(src)
        for folder in ("apps", "python"):
            if (root / folder).is_dir():
                findings += length_findings(root / folder)
    for finding in findings:
        print(finding)
    scope = "layering of " + str(src) if layering_only else f"{src}, {root / 'apps'} and {root / 'python'}"
    print(f"check_structure: {len(findings)} finding(s) ({scope})")
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
