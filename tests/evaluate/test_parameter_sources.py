"""ctest `report_parameter_sources`: the evaluation report's parameter table reads sources from the
files' comments (tools/report/parameter_sources.py), and says "no source" where they name none.

Usage: test_parameter_sources.py TOOLS_REPORT_DIR PLANT_YAML
"""
import os
import sys
import tempfile

FIXTURE = """# Legend: [PAPER] the paper; ESTIMATE our choice.
plant:
  timing:
    rate_Hz: 4000            # [Hz] no tag here
    period_s: 0.001          # [s] the Kortex cycle [KORTEX]
  # ESTIMATE: a comment block above the key names its source
  noise_std: 0.05
  enabled: true
  mjcf: ../arm.xml           # a file
  seed: 3
  gains:                     # the vendor loop's gains (ESTIMATE, see README)
    kp: [1, 2, 3]
    tf: [0.5, -0.2]          # [PAPER eq. H_tf]
  list_with_hash: ["#a", 2]  # [OURS] a '#' inside the list is not a comment
joints:
  - name: j1
    gear: 100                # [P-KORTEX]
  - name: j2
    gear: 50
"""


def main(argv):
    sys.path.insert(0, argv[1])
    from parameter_sources import markdown_table, parameter_rows

    failures = []

    def expect(condition, message):
        if not condition:
            failures.append(message)

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "plant.yaml")
        with open(path, "w") as f:
            f.write(FIXTURE)
        rows = {key: (value, source) for key, value, source in parameter_rows(path)}
    expect(rows["plant.timing.rate_Hz"] == ("4000", "no source"), f"rate_Hz: {rows.get('plant.timing.rate_Hz')}")
    expect(rows["plant.timing.period_s"][1] == "[KORTEX]", f"period_s: {rows.get('plant.timing.period_s')}")
    expect(rows["plant.noise_std"][1] == "ESTIMATE", f"noise_std: {rows.get('plant.noise_std')}")
    for key in ("plant.enabled", "plant.mjcf", "plant.seed"):
        expect(rows[key][1].startswith("setting"), f"{key}: {rows.get(key)}")
    # The section's comment is shown, but the value still has no source of its own.
    expect(rows["plant.gains.kp"][1].startswith("no source (its section says ESTIMATE"), f"kp: {rows.get('plant.gains.kp')}")
    expect(rows["plant.gains.tf"][1] == "[PAPER eq. H_tf]", f"tf: {rows.get('plant.gains.tf')}")
    expect(rows["plant.list_with_hash"] == ('["#a", 2]', "[OURS]"), f"list: {rows.get('plant.list_with_hash')}")
    expect(rows["joints[0].gear"] == ("100", "[P-KORTEX]"), f"joints[0].gear: {rows.get('joints[0].gear')}")
    expect(rows["joints[1].gear"] == ("50", "no source"), f"joints[1].gear: {rows.get('joints[1].gear')}")
    expect(len(rows) == 13, f"{len(rows)} parameters, expected 13: {sorted(rows)}")

    # The shipped plant file: every parameter found, the counts in the table's first line.
    plant_rows = parameter_rows(argv[2])
    table = markdown_table("plant", plant_rows)
    missing = sum(1 for r in plant_rows if r[2].startswith("no source"))
    expect(len(plant_rows) > 50, f"only {len(plant_rows)} parameters read from {argv[2]}")
    expect(table.splitlines()[0] == f"{len(plant_rows)} parameters in `plant`, {missing} with no source:", table.splitlines()[0])
    print(f"parameter sources: fixture ok; {argv[2]}: {len(plant_rows)} parameters, {missing} with no source")
    for f in failures:
        print("FAIL:", f)
    print(f"parameter sources checked: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
