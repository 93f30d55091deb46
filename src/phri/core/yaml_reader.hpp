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

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace phri {

class YamlReader {
public:
  /// Parses a YAML file; throws ConfigError(path, "", reason) when it cannot be read or parsed.
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

  /// A ConfigError for this node (key empty) or one of its keys.
  ConfigError error(std::string_view key, const std::string& reason) const;

private:
  YAML::Node node_;
  std::string file_;
  std::string path_;
};

}  // namespace phri
