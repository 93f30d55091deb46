"""examples/python/drops.py runs (short drops) and draws its figure."""
import os
import subprocess
import sys

from conftest import SOURCE_DIR


def test_drop_example_runs_and_writes_its_figure(tmp_path):
    out = tmp_path / "drops.png"
    done = subprocess.run([sys.executable, str(SOURCE_DIR / "examples/python/drops.py"), "--seconds", "1.0",
                           "--release", "0.2", "--out", str(out)], capture_output=True, text=True,
                          env={**os.environ, "MPLBACKEND": "Agg"}, check=True)
    rows = [line for line in done.stdout.splitlines() if line.startswith("| ") and "loop" in line and "drop" not in line]
    assert len(rows) == 3, done.stdout
    peaks = [float(row.split("|")[2]) for row in rows]
    assert all(20.0 < peak < 200.0 for peak in peaks)  # the cable jerked taut (1.25 kg, 25 cm, 2000 N/m)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
