#!/usr/bin/env python3
"""Regression test (ctest: cli_run_out_is_not_shell_code): an output folder named like shell code,
`phri run --out "o';touch X;'"`, is only a folder name. The run writes its log there and draws the
figure from it (core/process.hpp run_process: an argument vector, no shell), and no file X appears.

    no_shell_injection.py PHRI_BINARY CONFIG WORK_DIR
"""
import pathlib
import shutil
import subprocess
import sys


def main(binary, config, work_dir):
    work = pathlib.Path(work_dir)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    out = "o';touch X;'"
    command = [binary, "run", "--config", config, "--lockstep", "--duration", "0.05", "--out", out]
    result = subprocess.run(command, cwd=work, capture_output=True, text=True, timeout=120)
    report = f"command: {command}\nexit status: {result.returncode}\nstdout: {result.stdout}\nstderr: {result.stderr}"
    failures = []
    if result.returncode != 0:
        failures.append("the run failed")
    if not (work / out / "phri_demo.csv").is_file():
        failures.append(f"no log in the folder named {out!r}")
    injected = [str(p.relative_to(work)) for p in work.rglob("X")]
    if injected:
        failures.append(f"the shell ran the folder name: {injected} exist")
    if failures:
        sys.exit("; ".join(failures) + "\n" + report)
    print(f"no file X; the log is in {out!r}")


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
