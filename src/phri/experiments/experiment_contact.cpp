#include <phri/experiments/experiment_contact.hpp>

#include <phri/config/config.hpp>
#include <phri/core/format.hpp>
#include <phri/sim/sim_robot.hpp>

#include <algorithm>
#include <filesystem>
#include <sstream>

namespace phri {

std::optional<BodyRegionMap> experiment_body_regions(const std::string& regions_file, const std::string& plant_config_path) {
  const std::string file =
      regions_file.empty()
          ? (std::filesystem::path(plant_config_path).parent_path() / "iso_ts_15066_regions.yaml").string()
          : regions_file;
  if (regions_file.empty() && !std::filesystem::exists(file)) return std::nullopt;
  BodyRegionMap map;
  map.region = body_region_from_file(file, "lower_arm_wrist");
  const BodyRegion hand = body_region_from_file(file, "hand_fingers");
  map.links = {{"bracelet_link", hand}, {"end_effector_link", hand}};
  return map;
}

std::optional<ContactRecorder> experiment_contact(const Controller& cycle, const std::optional<BodyRegionMap>& regions) {
  if (!regions || !cycle.collision()) return std::nullopt;
  Eigen::VectorXd rotor(cycle.model().nv());
  for (int i = 0; i < rotor.size(); ++i) rotor[i] = cycle.actuators()[i].reflected_inertia_kgm2;
  return ContactRecorder(cycle.model(), *cycle.collision(), rotor, *regions);
}

void record_true_contact(std::optional<ContactRecorder>& recorder, const Controller& cycle, const SimRobot& robot) {
  if (recorder) recorder->record(cycle.model(), robot.truth().q_rad, robot.truth().qd_rad_s, robot.period_s());
}

void merge_contact(std::vector<ContactLinkSummary>& into, const std::vector<ContactLinkSummary>& more) {
  if (into.empty()) {
    into = more;
    return;
  }
  for (std::size_t i = 0; i < into.size() && i < more.size(); ++i) {
    ContactLinkSummary& a = into[i];
    const ContactLinkSummary& b = more[i];
    if (b.max_ratio > a.max_ratio) {
      a.max_ratio = b.max_ratio;
      a.speed_at_max_m_s = b.speed_at_max_m_s;
      a.reflected_mass_at_max_kg = b.reflected_mass_at_max_kg;
      a.permissible_speed_at_max_m_s = b.permissible_speed_at_max_m_s;
    }
    a.max_speed_m_s = std::max(a.max_speed_m_s, b.max_speed_m_s);
    a.max_energy_J = std::max(a.max_energy_J, b.max_energy_J);
    a.time_above_s += b.time_above_s;
  }
}

std::string contact_overview(const std::vector<std::pair<std::string, std::vector<ContactLinkSummary>>>& runs) {
  std::ostringstream s;
  bool any = false;
  for (const auto& [label, links] : runs) {
    if (links.empty()) continue;
    if (!any) {
      s << "\nPower and force limiting (ISO/TS 15066 transient contact, the plant's true state; regions as configs/demo.yaml's "
           "body_regions): the worst link of each run\n\n"
        << "| run | worst link (region) | max v / v_max | speed there [m/s] | v_max there [m/s] | longest time above 1 [s] |\n"
        << "|---|---|---|---|---|---|\n";
      any = true;
    }
    const auto worst = std::max_element(links.begin(), links.end(), [](const ContactLinkSummary& a, const ContactLinkSummary& b) {
      return a.max_ratio < b.max_ratio;
    });
    double above = 0.0;
    for (const ContactLinkSummary& l : links) above = std::max(above, l.time_above_s);
    s << "| " << label << " | " << worst->link << " (" << worst->region << ") | " << format_fixed(worst->max_ratio, 3) << " | "
      << format_fixed(worst->speed_at_max_m_s, 3) << " | " << format_fixed(worst->permissible_speed_at_max_m_s, 3) << " | "
      << format_fixed(above, 3) << " |\n";
  }
  return s.str();
}

}  // namespace phri
