#!/usr/bin/python3
"""Every parameter of a commented YAML file with its value and its source, for the evaluation report.

Usage: /usr/bin/python3 tools/report/parameter_sources.py FILE.yaml   (prints the markdown table)

A parameter is a key with a value (a scalar or a flow list/map) on its line; its path joins the keys
above it by indentation (plant.noise.torque_sensor_std_Nm). Its source is what the comments say: the
line's own comment and the comment block directly above it (up to a blank line or another key).
Recognised: bracketed tags ([PAPER ...], [DEMO 1.4], [KORTEX], [P-KINOVA], [UG-85], [OURS], ...), "(computed)",
ESTIMATE (our choice, argued in the comment), "Source: ..." and "(issue N default)"; a parameter
whose comments name none is "no source" (with what its section's comment says, which may be about
the section rather than the value); a switch, name, file or seed is a "setting".
"""
import re
import sys

# A source tag: two or more capitals, maybe with dashes and digits, then optional words
# ([PAPER eq. H_tf], [DEMO 1.4], [P-KORTEX], [UG-85], [BOTA, unverified]); units ([Hz], [N.m]) are not.
TAG = re.compile(r"\[[A-Z][A-Z-]*[A-Z][A-Z0-9-]*(?:[ ,][^\]]*)?\]")
KEY = re.compile(r"^(\s*)(- )?([A-Za-z_][A-Za-z0-9_]*):\s*(.*)$")


def split_comment(text):
    """(value, comment) of what follows a key's colon; '#' inside brackets or quotes is kept."""
    depth, quote = 0, None
    for i, c in enumerate(text):
        if quote:
            quote = None if c == quote else quote
        elif c in "'\"":
            quote = c
        elif c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        elif c == "#" and depth == 0 and (i == 0 or text[i - 1].isspace()):
            return text[:i].strip(), text[i + 1:].strip()
    return text.strip(), ""


def source_of(comments):
    text = " ".join(comments)
    found = [m.group(0) for m in TAG.finditer(text)]
    if "ESTIMATE" in text:
        found.append("ESTIMATE")
    if "Source:" in text:
        found.append("Source: " + text.split("Source:", 1)[1].split(".")[0].strip())
    if "(computed)" in text:
        found.append("computed from the others")
    issue = re.search(r"\(issue \d+ default\)", text)
    if issue:
        found.append(issue.group(0).strip("()"))
    seen = []
    for f in found:
        if f not in seen:
            seen.append(f)
    return ", ".join(seen) if seen else "no source"


def parameter_rows(path):
    """[(key path, value, source)] of every parameter of the file, in file order."""
    rows, stack, block = [], [], []
    with open(path) as f:
        lines = f.read().splitlines()
    for line in lines:
        stripped = line.strip()
        if not stripped:
            block = []
            continue
        if stripped.startswith("#"):
            block.append(stripped.lstrip("#").strip())
            continue
        m = KEY.match(line)
        if not m:
            block = []
            continue
        base = len(m.group(1))
        indent = base
        if m.group(2):  # "- key: ...": a new item of the list above, named [i] in the path
            while stack and stack[-1][0] >= base + 1:
                stack.pop()
            index = 0
            if stack:
                stack[-1][3] += 1
                index = stack[-1][3] - 1
            stack.append([base + 1, f"[{index}]", "no source", 0])
            indent = base + 2
        while stack and stack[-1][0] >= indent:
            stack.pop()
        key = m.group(3)
        value, comment = split_comment(m.group(4))
        path_text = join_path([k for _, k, _, _ in stack] + [key])
        source = source_of(block + [comment])
        if value:
            if source == "no source" and is_setting(key, value):
                source = "setting (not a physical value)"
            elif source == "no source":
                # A top-level key's comments are the file's legend, not a source.
                inherited = next((s for i, _, s, _ in reversed(stack) if i > 0 and s != "no source"), None)
                source = f"no source (its section says {inherited})" if inherited else source
            rows.append((path_text, value, source))
        else:
            stack.append([indent, key, source, 0])
        block = []
    return rows


def join_path(keys):
    """plant.noise.std, joints[0].friction.coulomb_Nm."""
    text = ""
    for k in keys:
        text += k if k.startswith("[") else ("." if text else "") + k
    return text


def is_setting(key, value):
    """A switch, a name, a file or a seed: chosen, not measured."""
    if value in ("true", "false") or key == "seed" or key.endswith("_seed"):
        return True
    try:
        float(value)
        return False
    except ValueError:
        return not value.startswith(("[", "{"))


def markdown_table(path, rows):
    missing = sum(1 for r in rows if r[2].startswith("no source"))
    out = [f"{len(rows)} parameters in `{path}`, {missing} with no source:", "",
           "| parameter | value | source |", "|---|---|---|"]
    for key, value, source in rows:
        shown = value if len(value) <= 60 else value[:57] + "..."
        out.append(f"| {key} | {shown.replace('|', '/')} | {source} |")
    return "\n".join(out)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__)
        sys.exit(2)
    print(markdown_table(sys.argv[1], parameter_rows(sys.argv[1])))
