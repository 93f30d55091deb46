#!/usr/bin/env python3
"""`phri run --log mcap` end to end (ctest: cli_log_mcap).

1. The demo for a few seconds with --log csv and with --log mcap (lockstep: the same rows);
   `phri log export --csv` of the MCAP equals the CSV in every column but cycle_time_s (the wall
   clock of each cycle's computation) and its legend equals the CSV's; the sizes are printed.
2. A run killed with SIGKILL after its second progress line: `phri log export` reads the file up to
   its last complete chunk (exit 0, "cut short", the rows up to then), `phri log info` too.
3. With node and the web packages (scripts/setup): the ecosystem's own readers (@mcap/core's indexed
   reader with its CRC checks, rosmsg2-serialization decoding every message by its schema;
   web/test/mcap_read.mjs) accept the complete file, and the killed one with --allow-truncated.

    mcap_log.py PHRI_BINARY CONFIG WORK_DIR [NODE]
"""
import pathlib
import shutil
import signal
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def run(command, **kwargs):
    return subprocess.run([str(c) for c in command], capture_output=True, text=True, **kwargs)


def same_rows_but_cycle_time(csv_a, csv_b):
    a, b = csv_a.read_text().splitlines(), csv_b.read_text().splitlines()
    if len(a) != len(b) or a[0] != b[0]:
        return False, f"{len(a)} vs {len(b)} lines"
    skip = a[0].split(",").index("cycle_time_s")
    for i, (x, y) in enumerate(zip(a, b)):
        fx, fy = x.split(","), y.split(",")
        del fx[skip], fy[skip]
        if fx != fy:
            return False, f"line {i + 1} differs"
    return True, f"{len(a) - 1} rows"


def round_trip(binary, config, work):
    for fmt in ("csv", "mcap"):
        result = run([binary, "run", "--config", config, "--lockstep", "--duration", "4", "--no-figure",
                      "--log", fmt, "--out", work / fmt])
        check(result.returncode == 0, f"phri run --log {fmt} exits 0 ({result.returncode}: {result.stderr.strip()})")
    csv = next((work / "csv").glob("*.csv"))
    mcap = next((work / "mcap").glob("*.mcap"), None)
    check(mcap is not None and not list((work / "mcap").glob("*.csv")), "--log mcap writes an .mcap and no CSV")
    if mcap is None:
        return None
    exported = work / "exported.csv"
    result = run([binary, "log", "export", mcap, "--csv", exported])
    check(result.returncode == 0 and "complete" in result.stdout, f"phri log export: {result.stdout.strip()}")
    same, detail = same_rows_but_cycle_time(exported, csv)
    check(same, f"the export equals the CSV run in every column but cycle_time_s ({detail})")
    legend = csv.with_name(csv.stem + ".legend.yaml")
    check(exported.with_name("exported.legend.yaml").read_text() == legend.read_text(), "the legends are the same")
    print(f"sizes: CSV {csv.stat().st_size} B, MCAP {mcap.stat().st_size} B, "
          f"ratio {csv.stat().st_size / mcap.stat().st_size:.2f}")
    return mcap


def killed_run(binary, config, work):
    out = work / "killed"
    command = [binary, "run", "--config", config, "--lockstep", "--duration", "30", "--no-figure", "--log", "mcap",
               "--out", out]
    process = subprocess.Popen([str(c) for c in command], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    progress = 0
    for line in process.stdout:
        progress += line.startswith("t ")
        if progress == 2:
            break
    process.send_signal(signal.SIGKILL)
    process.communicate()
    check(process.returncode == -signal.SIGKILL, f"the run was killed mid-way (status {process.returncode})")
    mcap = next(out.glob("*.mcap"))
    exported = work / "killed.csv"
    result = run([binary, "log", "export", mcap, "--csv", exported])
    rows = len(exported.read_text().splitlines()) - 1 if exported.exists() else 0
    check(result.returncode == 0 and "cut short" in result.stdout and rows >= 2000,
          f"the killed run's log exports up to its last chunk: {rows} rows ({result.stdout.strip()} {result.stderr.strip()})")
    result = run([binary, "log", "info", mcap])
    check(result.returncode == 0 and "/phri/cycle" in result.stdout, "phri log info reads the killed run's log")
    return mcap


def independent_read(node, complete, killed):
    reader = ROOT / "web" / "test" / "mcap_read.mjs"
    if not (ROOT / "web" / "node_modules" / "@mcap" / "core").is_dir():
        print("skip: the independent reader's packages are not installed (scripts/setup)")
        return
    result = run([node, reader, complete])
    check(result.returncode == 0, "@mcap/core and rosmsg2-serialization read the complete log" +
          ("" if result.returncode == 0 else f": {result.stdout[-600:]} {result.stderr[-600:]}"))
    result = run([node, reader, killed, "--allow-truncated"])
    ok = result.returncode == 0 and '"indexed": false' in result.stdout
    check(ok, "and the killed one, streamed up to its last chunk" +
          ("" if ok else f": {result.stdout[-600:]} {result.stderr[-600:]}"))


def main(binary, config, work_dir, node=None):
    work = pathlib.Path(work_dir)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    complete = round_trip(binary, config, work)
    killed = killed_run(binary, config, work)
    if node and complete is not None:
        independent_read(node, complete, killed)
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) not in (4, 5):
        print(__doc__)
        sys.exit(2)
    sys.exit(main(*sys.argv[1:]))
