#!/usr/bin/env python3
"""The mutated-configuration corpus (ctest: config_corpus_*, registered by tests/CMakeLists.txt).

Each case is a copy of the shipped configuration (configs/demo.yaml, configs/plant_gen3.yaml and
robots/kinova_gen3/*) with ONE nonsense mutation of one file. `phri run` must refuse every case
before any work: a non-zero exit status, nothing on stdout, exactly one line on stderr, and that
line names the key path (MENTIONS, checked by tests/cli/expect_one_error_line.cmake).

    make_corpus.py --list          one line per case: "<name>\\t<fragment>|<fragment>..." (for CMake)
    make_corpus.py --write DIR     writes DIR/<name>/{configs,robots/kinova_gen3}/... for every case,
                                   and DIR/unmutated/ (the copy itself, which must run)

Mutations (the table CASES below):
    ("set", "key.path[2].key", value)         a YAML value (PyYAML; comments are not kept)
    ("append", "key.path", item)              an item added to a YAML list
    ("text", "old", "new")                    the first occurrence of a text (YAML syntax cases:
                                              duplicate keys and nulls, which PyYAML cannot write)
    ("xml", "tag[@attr='v']/child", "attribute ...", value)   attributes of an XML element (URDF, MJCF)
    ("whole", text)                           the whole file replaced (an empty MJCF)
"""
import pathlib
import re
import shutil
import sys
import xml.etree.ElementTree as ET

import yaml

ROOT = pathlib.Path(__file__).resolve().parents[2]
DEMO = "configs/demo.yaml"
PLANT = "configs/plant_gen3.yaml"
URDF = "robots/kinova_gen3/gen3.urdf"
ACTUATORS = "robots/kinova_gen3/actuators.yaml"
COLLISION = "robots/kinova_gen3/collision.yaml"
MJCF = "robots/kinova_gen3/gen3_plant.xml"
REGIONS = "configs/iso_ts_15066_regions.yaml"
FILES = [DEMO, PLANT, URDF, ACTUATORS, COLLISION, MJCF, REGIONS]

# A folded posture within the joint limits whose wrist sits on the base (capsules interpenetrate).
FOLDED = [0.0, 2.2, 0.0, 2.5, 0.0, 2.0, 0.0]
GEN3_TORQUE_LIMITS = [95, 95, 95, 95, 26, 45, 26]
GEN3_VELOCITY_LIMITS = [2.09, 2.09, 2.09, 2.09, 3.05, 3.05, 3.05]

# A "billion laughs" of 9 levels of 9 aliases (387 million strings in ~550 bytes), as a top-level key.
ALIAS_BOMB = "lol0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + "".join(
    f"lol{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 9) + "]\n" for i in range(1, 9))

# name, file, mutation, fragments the error line must contain (the key path first).
CASES = [
    # -- YAML syntax: duplicate keys, explicit nulls
    ("demo_duplicate_key", DEMO, ("text", "observer_gain: 50.0", "observer_gain: 50.0\n  observer_gain: 5000.0"),
     ["controller.observer_gain", "duplicate key"]),
    ("demo_null_value", DEMO, ("text", "observer_gain: 50.0", "observer_gain: ~"), ["controller.observer_gain", "null"]),
    ("plant_null_value", PLANT, ("text", "current_std_A: 0.01", "current_std_A:"), ["plant.noise.current_std_A", "null"]),
    ("actuators_duplicate_key", ACTUATORS, ("text", "    gear_ratio: 100 ", "    gear_ratio: 10\n    gear_ratio: 100 "),
     ["actuators.yaml", "joints[0].gear_ratio", "duplicate key"]),
    ("collision_duplicate_key", COLLISION, ("text", "pairs:\n", "pairs: []\npairs:\n"), ["collision.yaml", "pairs", "duplicate key"]),
    # -- hostile YAML (issue 37): an alias bomb, an alias cycle, deep nesting
    ("yaml_alias_bomb", DEMO, ("text", "run:                                     # the run itself", ALIAS_BOMB + "run:"),
     ["demo.yaml", "alias bomb"]),
    ("yaml_alias_cycle", DEMO, ("text", "run:                                     # the run itself", "loop: &a [1, *a]\nrun:"),
     ["demo.yaml", "loop[1]", "cycle"]),
    ("yaml_deep_nesting", DEMO, ("text", "run:                                     # the run itself",
                                 "deep: " + "[" * 100 + "]" * 100 + "\nrun:"), ["demo.yaml", "nested deeper than 64 levels"]),
    ("yaml_deeper_than_the_parser", DEMO, ("text", "run:                                     # the run itself",
                                           "deep: " + "[" * 5000 + "]" * 5000 + "\nrun:"), ["demo.yaml", "nested too deeply"]),
    # -- sizes that exhausted memory
    ("run_duration_1e9", DEMO, ("set", "run.duration_s", 1e9), ["run.duration_s", "3600"]),
    ("log_buffer_4194304_rows", DEMO, ("set", "logging.buffer_rows", 4194304), ["logging.buffer_rows", "100 MiB"]),
    # -- a broken plant MJCF: MuJoCo's several lines as one
    ("mjcf_unknown_attribute", MJCF, ("xml", ".//joint[@name='joint_2']", "bogus", "1"), ["gen3_plant.xml", "bogus", "line"]),
    # MuJoCo 2.2.2 exits on an empty file after "Press Enter to exit" (issue 37).
    ("mjcf_empty", MJCF, ("whole", ""), ["gen3_plant.xml", "empty"]),
    ("mjcf_not_xml", MJCF, ("whole", "not a model\n"), ["gen3_plant.xml", "XML parse error"]),
    # -- URDF origins: urdfdom makes any finite rpy a finite quaternion (issue 37)
    ("urdf_joint_rpy_1e308", URDF, ("xml", "joint[@name='joint_3']/origin", "rpy", "1e308 0 0"),
     ["gen3.urdf", "joint 'joint_3' <origin> rpy", "beyond one turn"]),
    ("urdf_inertial_rpy_in_degrees", URDF, ("xml", "link[@name='forearm_link']/inertial/origin", "rpy", "0 90 0"),
     ["gen3.urdf", "link 'forearm_link' <origin> rpy", "degrees"]),
    ("urdf_joint_xyz_1e308", URDF, ("xml", "joint[@name='joint_5']/origin", "xyz", "0 1e308 0"),
     ["gen3.urdf", "joint 'joint_5' <origin> xyz", "100 m"]),
    # -- URDF inertials
    ("urdf_link_mass_1e300", URDF, ("xml", "link[@name='half_arm_1_link']/inertial/mass", "value", "1e300"),
     ["gen3.urdf", "link 'half_arm_1_link' <inertial>", "1000 kg"]),
    ("urdf_link_mass_2000kg", URDF, ("xml", "link[@name='forearm_link']/inertial/mass", "value", "2000"),
     ["link 'forearm_link' <inertial>", "1000 kg"]),
    ("urdf_link_mass_negative", URDF, ("xml", "link[@name='forearm_link']/inertial/mass", "value", "-1"),
     ["link 'forearm_link' <inertial>", "mass must be positive"]),
    ("urdf_inertia_negative", URDF, ("xml", "link[@name='shoulder_link']/inertial/inertia", "ixx", "-0.01"),
     ["link 'shoulder_link' <inertial>", "positive definite"]),
    ("urdf_inertia_nan", URDF, ("xml", "link[@name='shoulder_link']/inertial/inertia", "iyy", "nan"),
     ["link 'shoulder_link' <inertial>", "iyy"]),
    # urdfdom logs "Could not parse inertial element" and zeroes the mass; phri refuses it (issue 16).
    # (An inertia that breaks the triangle inequality is accepted with a warning since issue 16.)
    ("urdf_link_mass_with_unit", URDF, ("xml", "link[@name='forearm_link']/inertial/mass", "value", "0.9302kg"),
     ["link 'forearm_link' <inertial>", "0.9302kg"]),
    ("urdf_inertia_absurd", URDF, ("xml", "link[@name='bracelet_link']/inertial/inertia", "ixx iyy izz", "5000"),
     ["link 'bracelet_link' <inertial>", "radius of gyration"]),
    # -- URDF joints against the hinge plant
    ("urdf_joint_prismatic", URDF, ("xml", "joint[@name='joint_2']", "type", "prismatic"), ["joint 'joint_2'", "prismatic"]),
    ("urdf_joint_limits_200rad", URDF, ("xml", "joint[@name='joint_4']/limit", "upper", "200"),
     ["joint 'joint_4' <limit>", "2 pi"]),
    ("urdf_joint_limits_wider_than_plant", URDF, ("xml", "joint[@name='joint_6']/limit", "upper", "2.8"),
     ["joint 'joint_6' <limit>", "plant"]),
    ("urdf_joint_continuous_plant_limited", URDF, ("xml", "joint[@name='joint_2']", "type", "continuous"),
     ["joint 'joint_2'", "unlimited in the URDF"]),
    # -- postures beyond the joint limits, or in self-collision
    ("initial_q_beyond_limit", PLANT, ("set", "plant.initial.q_rad[1]", 3.0), ["plant.initial.q_rad[1]", "joint_2"]),
    ("home_q_beyond_limit", DEMO, ("set", "fsm.startup.home_q_rad[3]", -2.8), ["fsm.startup.home_q_rad[3]", "joint_4"]),
    ("static_posture_beyond_limit", DEMO, ("set", "fsm.static.posture_q_rad[5]", 2.5), ["fsm.static.posture_q_rad[5]", "joint_6"]),
    ("initial_q_in_collision", PLANT, ("set", "plant.initial.q_rad", FOLDED), ["plant.initial.q_rad", "self-collision"]),
    ("home_q_in_collision", DEMO, ("set", "fsm.startup.home_q_rad", FOLDED), ["fsm.startup.home_q_rad", "self-collision"]),
    ("static_posture_in_collision", DEMO, ("set", "fsm.static.posture_q_rad", FOLDED),
     ["fsm.static.posture_q_rad", "self-collision"]),
    ("posture_in_degrees", DEMO, ("set", "fsm.static.posture_q_rad[2]", 180.0), ["fsm.static.posture_q_rad[2]", "must be in"]),
    # -- plant sensors and vendor loops
    ("encoder_1_count_per_rev", PLANT, ("set", "plant.noise.encoder_counts_per_rev", 1), ["plant.noise.encoder_counts_per_rev", "4096"]),
    ("torque_sensor_noise_5Nm", PLANT, ("set", "plant.noise.torque_sensor_std_Nm", 5.0), ["plant.noise.torque_sensor_std_Nm"]),
    ("vendor_filter_unstable", PLANT, ("set", "plant.vendor.torque_high_velocity.denominator", [1.0, -2.1, 1.2]),
     ["plant.vendor.torque_high_velocity.denominator", "unstable"]),
    ("vendor_filter_huge_coefficient", PLANT, ("set", "plant.vendor.torque_high_velocity.numerator[0]", 1e6),
     ["plant.vendor.torque_high_velocity.numerator[0]"]),
    ("vendor_kp_1e6", PLANT, ("set", "plant.vendor.position.kp_Nm_per_rad[0]", 1e6), ["plant.vendor.position.kp_Nm_per_rad[0]"]),
    ("vendor_kd_1e5", PLANT, ("set", "plant.vendor.position.kd_Nms_per_rad[2]", 1e5), ["plant.vendor.position.kd_Nms_per_rad[2]"]),
    ("vendor_ki_1e7", PLANT, ("set", "plant.vendor.position.ki_Nm_per_rad_s[1]", 1e7), ["plant.vendor.position.ki_Nm_per_rad_s[1]"]),
    ("vendor_integral_limit_above_drive", PLANT, ("set", "plant.vendor.position.integral_limit_Nm[4]", 80),
     ["plant.vendor.position.integral_limit_Nm[4]", "drive maximum"]),
    ("vendor_torque_damping_1e3", PLANT, ("set", "plant.vendor.torque.velocity_damping_Nms_per_rad[0]", 1000),
     ["plant.vendor.torque.velocity_damping_Nms_per_rad[0]"]),
    ("plant_tool_100kg", PLANT, ("set", "plant.tool.mass_kg", 100), ["plant.tool.mass_kg"]),
    # -- the plant's drives (issue 16): whose, and a generic hold's gains
    ("plant_drive_unknown", PLANT, ("set", "plant.drive", "franka"), ["plant.drive", "kinova, generic"]),
    ("plant_drive_generic_with_vendor", PLANT, ("set", "plant.drive", "generic"), ["plant.vendor", "generic"]),
    ("plant_drive_kinova_with_hold_gains", PLANT,
     ("set", "plant.drive", {"kind": "kinova", "position_hold": {"kp_Nm_per_rad": [3000] * 7}}),
     ["plant.drive.position_hold", "vendor"]),
    ("drop_mass_100kg", PLANT, ("set", "plant.drop_test.mass_kg", 100), ["plant.drop_test.mass_kg"]),
    ("push_force_1e4N", DEMO, ("set", "plant.disturbances[0].force_N[1]", 1e4), ["plant.disturbances[0].force_N[1]"]),
    # -- actuators.yaml
    ("actuator_torque_limit_above_drive", ACTUATORS, ("set", "joints[0].torque_limit_Nm", 500),
     ["actuators.yaml", "joints[0].torque_limit_Nm", "drive's maximum"]),
    ("actuator_torque_limit_tiny", ACTUATORS, ("set", "joints[5].torque_limit_Nm", 1e-6), ["joints[5].torque_limit_Nm"]),
    ("actuator_current_1e4A", ACTUATORS, ("set", "joints[1].current_limit_A", 1e4), ["joints[1].current_limit_A"]),
    ("actuator_velocity_in_degrees", ACTUATORS, ("set", "joints[2].velocity_limit_rad_s", 120),
     ["joints[2].velocity_limit_rad_s"]),
    ("actuator_static_friction_above_drive", ACTUATORS, ("set", "joints[4].friction.static_Nm", 60),
     ["joints[4].friction.static_Nm", "drive's maximum"]),
    ("actuator_gear_ratio_1e5", ACTUATORS, ("set", "joints[3].gear_ratio", 1e5), ["joints[3].gear_ratio"]),
    # -- the controller's QP overrides
    ("qp_torque_limit_above_drive", DEMO, ("set", "controller.qp.torque_limit_Nm", [500] + GEN3_TORQUE_LIMITS[1:]),
     ["controller.qp.torque_limit_Nm[0]", "drive maximum"]),
    ("qp_torque_limit_tiny", DEMO, ("set", "controller.qp.torque_limit_Nm", GEN3_TORQUE_LIMITS[:6] + [1e-6]),
     ["controller.qp.torque_limit_Nm[6]"]),
    ("qp_velocity_limit_in_degrees", DEMO, ("set", "controller.qp.velocity_limit_rad_s", [120] + GEN3_VELOCITY_LIMITS[1:]),
     ["controller.qp.velocity_limit_rad_s[0]"]),
    # -- collision.yaml
    ("collision_radius_5m", COLLISION, ("set", "capsules[3].radius", 5.0), ["collision.yaml", "capsules[3].radius"]),
    ("collision_adjacent_pair", COLLISION, ("append", "pairs", ["forearm_link", "spherical_wrist_1_link"]),
     ["collision.yaml", "pairs[18]", "joint_5"]),
    # -- robot: payloads, end-effector frame
    ("payload_100kg", DEMO, ("set", "robot.payloads[1].mass_kg", 100), ["robot.payloads[1].mass_kg"]),
    ("payload_negative_mass", DEMO, ("set", "robot.payloads[0].mass_kg", -0.3), ["robot.payloads[0].mass_kg"]),
    ("payload_nan_mass", DEMO, ("set", "robot.payloads[0].mass_kg", float("nan")), ["robot.payloads[0].mass_kg", "finite"]),
    ("end_effector_frame_base", DEMO, ("set", "robot.end_effector_frame", "base_link"),
     ["robot.end_effector_frame", "not moved by any joint"]),
    ("end_effector_frame_upstream", DEMO, ("set", "robot.end_effector_frame", "forearm_link"),
     ["robot.end_effector_frame", "upstream of the last joint"]),
    # -- controller gains and filters
    ("observer_gain_unstable", DEMO, ("set", "controller.observer_gain", 2500.0), ["controller.observer_gain", "period_s"]),
    ("posture_damping_5000", DEMO, ("set", "controller.compliance.posture_damping", 5000.0),
     ["controller.compliance.posture_damping"]),
    ("wrench_tool_100kg", DEMO, ("set", "controller.wrench.tool_mass_kg", 100), ["controller.wrench.tool_mass_kg"]),
    ("custom_transfer_gain_500", DEMO, ("set", "low_level.custom.transfer_gain", 500.0), ["low_level.custom.transfer_gain"]),
    ("custom_integral_leak_1e4", DEMO, ("set", "low_level.custom.integral_leak", 1e4), ["low_level.custom.integral_leak"]),
    ("custom_integral_gain_1e4", DEMO, ("set", "low_level.custom.integral_gain", 1e4), ["low_level.custom.integral_gain"]),
    # -- values that loaded and meant nothing (issue 37)
    ("collision_safety_distance_0", DEMO, ("set", "controller.qp.collision.safety_distance_m", 0),
     ["controller.qp.collision.safety_distance_m", "> 0"]),
    ("qp_velocity_fraction_1e-9", DEMO, ("set", "controller.qp.velocity_limit_fraction", 1e-9),
     ["controller.qp.velocity_limit_fraction", "[0.05, 1]"]),
    ("wrench_bias_samples_0", DEMO, ("set", "controller.wrench.bias_samples", 0), ["controller.wrench.bias_samples", "[1, 1000000]"]),
]

PATH_PART = re.compile(r"([^.\[\]]+)|\[(\d+)\]")


def split_path(path):
    return [int(index) if index else key for key, index in PATH_PART.findall(path)]


def set_in(document, path, value, append=False):
    parts = split_path(path)
    node = document
    for part in parts[:-1]:
        node = node[part]
    if append:
        node[parts[-1]].append(value)
        return
    if isinstance(parts[-1], str) or parts[-1] < len(node):
        node[parts[-1]] = value
    else:
        raise KeyError(path)


def mutate(text, mutation):
    kind = mutation[0]
    if kind == "text":
        _, old, new = mutation
        if old not in text:
            raise ValueError(f"'{old}' not found")
        return text.replace(old, new, 1)
    if kind in ("set", "append"):
        document = yaml.safe_load(text)
        set_in(document, mutation[1], mutation[2], append=kind == "append")
        return yaml.safe_dump(document, sort_keys=False, default_flow_style=None, width=1000)
    if kind == "whole":
        return mutation[1]
    if kind == "xml":
        _, where, attribute, value = mutation
        root = ET.fromstring(text)
        found = root.findall(where)
        if len(found) != 1:
            raise ValueError(f"{len(found)} elements match '{where}'")
        for name in attribute.split():
            found[0].set(name, value)
        return ET.tostring(root, encoding="unicode")
    raise ValueError(f"unknown mutation kind '{kind}'")


def copy_configuration(target):
    for relative in FILES:
        destination = target / relative
        destination.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / relative, destination)


def write(out_dir):
    out_dir = pathlib.Path(out_dir)
    shutil.rmtree(out_dir, ignore_errors=True)
    copy_configuration(out_dir / "unmutated")
    for name, relative, mutation, _ in CASES:
        case = out_dir / name
        copy_configuration(case)
        path = case / relative
        try:
            path.write_text(mutate(path.read_text(), mutation))
        except (KeyError, IndexError, ValueError) as error:
            sys.exit(f"make_corpus.py: case {name}: cannot apply {mutation} to {relative}: {error}")
        (case / "MUTATION.txt").write_text(f"{relative}: {mutation!r}\n")


def main(argv):
    names = [case[0] for case in CASES]
    if len(set(names)) != len(names):
        sys.exit("make_corpus.py: two cases share a name")
    if argv[1:2] == ["--list"]:
        for name, _, _, mentions in CASES:
            print(name + "\t" + "|".join(mentions))
    elif argv[1:2] == ["--write"] and len(argv) == 3:
        write(argv[2])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv)
