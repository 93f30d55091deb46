#pragma once
// What each experiment reports of power and force limiting (ISO/TS 15066 transient contact,
// control/power_force_limit.hpp): every link's largest v / v_max on the plant's true state, against
// the body regions phri run's demo declares (configs/demo.yaml, `body_regions`): a lower arm or
// wrist for any link, a hand for the wrist's bracelet and the tool [OURS: a person beside a
// table-height cell; the workcell's risk assessment decides]. The figures judge the motion; they
// change nothing the arm does.
#include <phri/control/controller.hpp>
#include <phri/control/power_force_limit.hpp>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace phri {

class SimRobot;

/// The demo's body regions, from `regions_file` (configs/iso_ts_15066_regions.yaml's form); empty:
/// the iso_ts_15066_regions.yaml in the folder of `plant_config_path` (the shipped configs/), and
/// none (no figures) when that folder has none. ConfigError when a named file lacks a region.
std::optional<BodyRegionMap> experiment_body_regions(const std::string& regions_file, const std::string& plant_config_path);

/// A recorder of `cycle`'s links; none without regions or when the controller has no capsules.
std::optional<ContactRecorder> experiment_contact(const Controller& cycle, const std::optional<BodyRegionMap>& regions);
/// Records one cycle of the plant's true state (nothing without a recorder).
void record_true_contact(std::optional<ContactRecorder>& recorder, const Controller& cycle, const SimRobot& robot);

/// Per link, the larger of both maxima and the summed time above 1 (runs of the same arm).
void merge_contact(std::vector<ContactLinkSummary>& into, const std::vector<ContactLinkSummary>& more);

/// One markdown row per run (label, its links): the worst link, its v / v_max and the speed and
/// v_max there, the longest time above 1 of any link. Empty when no run measured anything.
std::string contact_overview(const std::vector<std::pair<std::string, std::vector<ContactLinkSummary>>>& runs);

}  // namespace phri
