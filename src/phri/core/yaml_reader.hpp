#pragma once
// phri::YamlReader: a YAML node that knows its file and its key path, for configuration loaders
// that validate as they read (DESIGN.md section 5: unknown keys are errors, wrong types and
// out-of-range values are errors; every error is a phri::ConfigError naming file and key path,
// e.g. "configs/plant_gen3.yaml: plant.noise.torque_sensor_std_Nm: must be in [0, 10], got -1").
//
//   const phri::YamlReader root = phri::YamlReader::load_file(path);
//   const phri::YamlReader plant = root.at("plant");
//   plant.allow_keys({"seed", "noise"});
//   const auto seed = plant.integer_or("seed", 1, 0, 1 << 30);
//
// Internal to phri's loaders: yaml-cpp is a private dependency of libphri, so only phri's own .cpp
// files include this header (it is installed with the others but needs yaml-cpp's headers).
#include <phri/core/error.hpp>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <initializer_list>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace phri {

/// What resolve_path does with a relative result (see there).
enum class PathForm {
  kAsGiven,   ///< base_dir / file, relative when base_dir is
  kAbsolute,  ///< anchored at the working directory
};

/// `file` as named in a YAML file whose folder is `base_dir`: an absolute `file` stays as it is
/// (normalised), a relative one is joined to `base_dir`. The plant loader keeps paths in the form
/// it was given (kAsGiven: the paths it reports are the caller's); the run configuration makes
/// them absolute (kAbsolute) so that the plant loader, resolving them again against its own base
/// folder, cannot prefix them a second time.
std::string resolve_path(const std::string& base_dir, const std::string& file, PathForm form);

class YamlReader {
public:
  /// Parses a YAML file; throws ConfigError(path, "", reason) when it cannot be read or parsed, and
  /// ConfigError(path, key path, reason) for a key given twice in one map or an explicit null value
  /// (`key:`, `key: ~`): yaml-cpp would keep the first silently, a loader would take null as absent.
  static YamlReader load_file(const std::string& path);
  /// Parses YAML text; `source_name` stands for the file name in error messages.
  static YamlReader load_string(const std::string& text, const std::string& source_name);

  YamlReader(YAML::Node node, std::string file, std::string path);

  const std::string& file() const { return file_; }
  /// Key path of this node ("" for the document root), e.g. "plant.disturbances[2]".
  const std::string& path() const { return path_; }
  /// Key path of a child key of this node.
  std::string path_of(std::string_view key) const;

  bool is_map() const { return node_.IsMap(); }
  bool is_sequence() const { return node_.IsSequence(); }
  bool is_null() const { return !node_ || node_.IsNull(); }
  /// Throws unless this node is a map (an empty/null node counts as an empty map).
  void expect_map() const;
  /// Throws unless this node is a sequence.
  void expect_sequence() const;
  /// Throws on the first key of this map not in `keys` ("unknown key").
  void allow_keys(std::initializer_list<std::string_view> keys) const;

  /// Keys of a map, in file order (empty for null).
  std::vector<std::string> keys() const;
  /// True if the map has `key` with a non-null value.
  bool has(std::string_view key) const;
  /// Child of a map; throws ConfigError("missing key") when absent.
  YamlReader at(std::string_view key) const;
  /// Number of elements of a sequence (0 for null).
  std::size_t size() const;
  /// Element of a sequence.
  YamlReader at(std::size_t index) const;

  // Scalars of this node itself.
  double as_number(double min, double max) const;
  long long as_integer(long long min, long long max) const;
  bool as_boolean() const;
  std::string as_text() const;

  // Scalars under a key of this map: required, or with a fallback when the key is absent.
  double number(std::string_view key, double min, double max) const;
  double number_or(std::string_view key, double fallback, double min, double max) const;
  long long integer(std::string_view key, long long min, long long max) const;
  long long integer_or(std::string_view key, long long fallback, long long min, long long max) const;
  bool boolean(std::string_view key) const;
  bool boolean_or(std::string_view key, bool fallback) const;
  std::string text(std::string_view key) const;
  std::string text_or(std::string_view key, const std::string& fallback) const;
  /// One of `choices`.
  std::string choice(std::string_view key, std::initializer_list<std::string_view> choices) const;
  std::string choice_or(std::string_view key, const std::string& fallback,
                        std::initializer_list<std::string_view> choices) const;
  /// A sequence of numbers; `expected_size` < 0 accepts any length.
  std::vector<double> numbers(std::string_view key, int expected_size, double min, double max) const;
  /// Exactly `dof` numbers, one per joint, as std::vector<double> or Eigen::VectorXd.
  template <class Vector = std::vector<double>>
  Vector per_joint(std::string_view key, int dof, double min, double max) const;
  /// Three numbers (a point, a force, principal inertias...).
  Eigen::Vector3d vector3(std::string_view key, double min, double max) const;
  Eigen::Vector3d vector3_or(std::string_view key, const Eigen::Vector3d& fallback, double min, double max) const;

  /// The node itself, for loaders that compose documents (merging a file with overrides).
  const YAML::Node& node() const { return node_; }

  /// A ConfigError for this node (key empty) or one of its keys.
  ConfigError error(std::string_view key, const std::string& reason) const;

private:
  YAML::Node node_;
  std::string file_;
  std::string path_;
};

template <class Vector>
Vector YamlReader::per_joint(std::string_view key, int dof, double min, double max) const {
  static_assert(std::is_same_v<Vector, std::vector<double>> || std::is_same_v<Vector, Eigen::VectorXd>);
  std::vector<double> values = numbers(key, dof, min, max);
  if constexpr (std::is_same_v<Vector, Eigen::VectorXd>) {
    return Eigen::Map<const Eigen::VectorXd>(values.data(), dof);
  } else {
    return values;
  }
}

}  // namespace phri
