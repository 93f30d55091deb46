#!/usr/bin/env python3
"""`phri run` ended by a signal (issue 37; ctest: cli_run_stops_on_sigterm, cli_run_stops_on_sigint).

Starts a lockstep run of the demo with stdout a pipe, waits for the second progress line (t = 5 s:
a log of some rows), checks the program is still running when it arrives (stdout is line-buffered,
not flushed only at exit), sends the signal, and checks the run ended through its normal end: exit status 128 + the signal's number,
the progress line, summary.md (saying INTERRUPTED, fewer cycles than asked), the log with its rows,
the figure when asked, and one line on stderr saying so.

    stop_on_signal.py PHRI_BINARY CONFIG WORK_DIR TERM|INT [--figure]
"""
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import time

DURATION_S = 30  # far longer than the test waits: the signal must end it


def main(binary, config, work_dir, signal_name, figure):
    number = {"TERM": signal.SIGTERM, "INT": signal.SIGINT}[signal_name]
    work = pathlib.Path(work_dir)
    shutil.rmtree(work, ignore_errors=True)
    command = [binary, "run", "--config", config, "--lockstep", "--duration", str(DURATION_S), "--out", str(work)]
    if not figure:
        command.append("--no-figure")
    started = time.monotonic()
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    before, progress = [], 0
    for line in process.stdout:  # each line as soon as phri writes it out
        before.append(line)
        progress += line.startswith("t ")
        if progress == 2:
            break
    failures = []
    running = process.poll() is None
    if progress < 2:
        failures.append("fewer than two progress lines before the end of stdout")
    elif not running:
        failures.append("the progress lines arrived only when phri had exited (stdout block-buffered?)")
    process.send_signal(number)
    try:
        rest, err = process.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        process.kill()
        rest, err = process.communicate()
        failures.append("phri did not end within 120 s of the signal")
    elapsed = time.monotonic() - started
    stdout = "".join(before) + rest
    report = (f"command: {command}\nexit status: {process.returncode}\nwall time: {elapsed:.1f} s\n"
              f"stdout: {stdout}\nstderr: {err}")
    if process.returncode != 128 + number:
        failures.append(f"exit status {process.returncode}, expected {128 + number}")
    summary = work / "summary.md"
    if not summary.is_file():
        failures.append("no summary.md")
    else:
        text = summary.read_text()
        cycles = re.search(r"(\d+) cycles", text)
        if "INTERRUPTED" not in text:
            failures.append("summary.md does not say INTERRUPTED")
        if not cycles or int(cycles.group(1)) >= DURATION_S * 1000:
            failures.append(f"summary.md does not show an early end: {cycles.group(0) if cycles else 'no cycle count'}")
    log = work / "phri_demo.csv"
    if not log.is_file() or len(log.read_text().splitlines()) < 2:
        failures.append("no log, or a log without rows")
    if figure and not (work / "demo.png").is_file():
        failures.append("no figure (demo.png)")
    if f"phri: interrupted by SIG{signal_name}" not in err:
        failures.append(f"stderr does not say 'phri: interrupted by SIG{signal_name}'")
    if failures:
        sys.exit("; ".join(failures) + "\n" + report)
    print(f"SIG{signal_name}: exit status {process.returncode} after {elapsed:.1f} s; {cycles.group(0)}; "
          f"progress line while running: {before[-1].strip()}")


if __name__ == "__main__":
    if len(sys.argv) not in (5, 6) or sys.argv[4] not in ("TERM", "INT") or sys.argv[5:] not in ([], ["--figure"]):
        sys.exit(__doc__)
    main(*sys.argv[1:5], figure=sys.argv[5:] == ["--figure"])
