#pragma once
// Physical ranges shared by the run YAML (config/config.cpp) and the robot bundle
// (config/robot_bundle.cpp): a value beyond them is a unit mistake or a typo, not a setting.
namespace phri::physical_range {

// What an arm carries beyond its URDF: at most 20 kg, 5x the Gen3's rated 4 kg payload (above, a
// unit mistake), inertia at most 1 kg.m^2 (20 kg at a 0.22 m radius of gyration).
constexpr double kMaxPayload_kg = 20.0;
constexpr double kMaxPayloadInertia_kgm2 = 1.0;
// A joint position beyond one turn each way is a typo (degrees for radians), not a posture.
constexpr double kMaxJointAngle_rad = 2.0 * 3.14159265358979323846;

}  // namespace phri::physical_range
