#pragma once
// The protocol of each evaluation as it ran: every parameter the experiment's options set (not the
// plant's or the drives', which the plant and actuator files state with their own comments), with
// its value and its source. A source names the paper ([PAPER] its text, [DEMO] its code, as
// transcribed in the reference notes), an issue's protocol, or says "no source" with what the value
// is for; a switch or a seed is a "setting". `phri evaluate` writes the rows to protocol.csv and the
// report prints them as one table, so that no number of a result is left without its origin.
#include <string>
#include <vector>

namespace phri {

struct DropTestOptions;
struct DualComplianceOptions;
struct FrictionIdentificationOptions;
struct TorqueTrackingOptions;

struct ProtocolParameter {
  std::string experiment;  ///< the report's name of the evaluation
  std::string parameter;
  std::string value;  ///< with its unit
  std::string source;
};

class ProtocolTable {
public:
  void add(const std::string& experiment, const std::string& parameter, const std::string& value,
           const std::string& source);
  const std::vector<ProtocolParameter>& rows() const { return rows_; }
  /// "experiment,parameter,value,source" and one quoted row per parameter.
  std::string csv() const;

  void add_friction_identification(const std::string& experiment, const FrictionIdentificationOptions& o);
  /// The static and dynamic scenarios' rows as `o` runs them (the loops, the scenarios it lists).
  void add_torque_tracking(const std::string& experiment, const TorqueTrackingOptions& o);
  void add_drop_test(const std::string& experiment, const DropTestOptions& o);
  void add_dual_compliance(const std::string& experiment, const DualComplianceOptions& o);

private:
  std::vector<ProtocolParameter> rows_;
};

}  // namespace phri
