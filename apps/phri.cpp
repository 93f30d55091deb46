// phri: the command-line entry point.
#include <phri/core/config_error.hpp>
#include <phri/core/version.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/model.hpp>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

namespace {

// Prints what the model loaded from a URDF: joints, limits, masses, and a few sanity figures.
int print_model_summary(const std::string& urdf_path, const std::string& tip, const std::string& frame_name) {
  phri::ModelOptions options;
  options.tip_link = tip;
  const phri::Model model = phri::Model::from_urdf_file(urdf_path, options);
  phri::Data data(model);
  std::printf("model '%s' from %s\n", model.name().c_str(), urdf_path.c_str());
  std::printf("chain %s -> %s: %d joints, %d frames, moving mass %.4f kg\n\n", model.base_link().c_str(),
              model.tip_link().c_str(), model.nq(), model.num_frames(), model.total_mass());
  std::printf("%-3s %-10s %-11s %10s %10s %10s %10s %9s\n", "#", "joint", "type", "lower", "upper",
              "vel.lim", "effort", "mass kg");
  for (int i = 0; i < model.nq(); ++i) {
    const phri::Joint& j = model.joint(i);
    const char* type = j.type == phri::JointType::kPrismatic ? "prismatic"
                       : j.type == phri::JointType::kContinuous ? "continuous" : "revolute";
    std::printf("%-3d %-10s %-11s %10.4f %10.4f %10.4f %10.2f %9.4f\n", i + 1, j.name.c_str(), type, j.lower,
                j.upper, j.velocity_limit, j.effort_limit, model.body_inertia(i).mass);
  }
  const int frame = model.frame_id(frame_name.empty() ? model.tip_link() : frame_name);
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(model.nq());
  phri::compute_all_terms(model, data, q0, q0);
  phri::compute_gravity(model, data, q0);
  const Eigen::Vector3d p = data.frame_placements[static_cast<std::size_t>(frame)].translation();
  std::printf("\nat q = 0: %s at (%.6f, %.6f, %.6f) m; |g(q)| = %.4f N.m; M diagonal:",
              model.frame(frame).name.c_str(), p.x(), p.y(), p.z(), data.gravity_torque.norm());
  for (int i = 0; i < model.nq(); ++i) std::printf(" %.4f", data.mass_matrix(i, i));
  std::printf("\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"phri: control framework for physical human-robot interaction"};
  app.set_version_flag("--version", std::string("phri ") + phri::version());
  app.require_subcommand(1);

  auto* info = app.add_subcommand("info", "Load a robot description and print a summary of its model");
  std::string urdf_path;
  std::string tip;
  std::string frame;
  info->add_option("--urdf", urdf_path, "URDF file")->required();
  info->add_option("--tip", tip, "tip link of the chain (default: end of the movable chain)");
  info->add_option("--frame", frame, "frame whose position is printed (default: the tip)");

  CLI11_PARSE(app, argc, argv);
  try {
    if (info->parsed()) return print_model_summary(urdf_path, tip, frame);
  } catch (const phri::ConfigError& e) {
    std::fprintf(stderr, "phri: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
