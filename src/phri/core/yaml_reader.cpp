#include <phri/core/yaml_reader.hpp>

#include <phri/core/format.hpp>

#include <yaml-cpp/depthguard.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace phri {
namespace {

// Significant digits of the numbers in error messages.
constexpr int kMessageDigits = 10;

std::string child_path(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

// Bounds of a document's walk. yaml-cpp shares an aliased node instead of copying it, so a few
// hundred bytes of nested aliases ("billion laughs") stand for 10^9 nodes, and an alias inside its
// own anchor (`&a [*a]`) is a cycle: the walk counts every node it reaches (through aliases too)
// and refuses a document past kMaxNodes or kMaxDepth, long before the loaders would walk it.
// Configuration files have a few thousand nodes at most and nest fewer than 10 levels.
constexpr std::size_t kMaxNodes = 100000;
constexpr std::size_t kMaxDepth = 64;

// What yaml-cpp lets through silently, refused for the whole document as soon as it is parsed:
// a key given twice in one map (yaml-cpp keeps both, and node[key] answers the first) and a key
// whose value is an explicit null (`key:`, `key: ~`, `key: null`), which the loaders would take as
// "absent" and replace by the default. No configuration file documents null as a value: to use the
// default, leave the key out. Also the bounds above.
class DocumentCheck {
public:
  explicit DocumentCheck(const std::string& file) : file_(file) {}

  void check(const YAML::Node& node, const std::string& path) {
    if (++nodes_ > kMaxNodes) {
      throw ConfigError(file_, path, "more than " + std::to_string(kMaxNodes) +
                                         " YAML nodes counting those reached through aliases (an alias bomb?)");
    }
    for (const YAML::Node& ancestor : ancestors_) {
      if (node.is(ancestor)) throw ConfigError(file_, path, "an alias refers to a node that contains it (a cycle)");
    }
    if (ancestors_.size() >= kMaxDepth) {
      // The key path's head says where; 64 levels of it would fill the line.
      const std::string shown = path.size() > 60 ? path.substr(0, 60) + "..." : path;
      throw ConfigError(file_, shown, "nested deeper than " + std::to_string(kMaxDepth) + " levels");
    }
    if (!node.IsSequence() && !node.IsMap()) return;
    ancestors_.push_back(node);
    if (node.IsSequence()) {
      for (std::size_t i = 0; i < node.size(); ++i) check(node[i], path + "[" + std::to_string(i) + "]");
    } else {
      check_map(node, path);
    }
    ancestors_.pop_back();
  }

private:
  void check_map(const YAML::Node& node, const std::string& path) {
    std::vector<std::string> seen;
    for (const auto& item : node) {
      if (!item.first.IsScalar()) throw ConfigError(file_, path, "keys must be strings");
      const std::string key = item.first.Scalar();
      const std::string key_path = child_path(path, key);
      if (std::find(seen.begin(), seen.end(), key) != seen.end()) {
        throw ConfigError(file_, key_path, "duplicate key (given twice in the same map)");
      }
      seen.push_back(key);
      if (!item.second || item.second.IsNull()) {
        throw ConfigError(file_, key_path, "no value (explicit null); leave the key out to use the default");
      }
      check(item.second, key_path);
    }
  }

  const std::string& file_;
  std::size_t nodes_ = 0;
  std::vector<YAML::Node> ancestors_;
};

}  // namespace

std::string resolve_path(const std::string& base_dir, const std::string& file, PathForm form) {
  // An absolute `file` replaces base_dir in the join; an empty base_dir leaves `file` as it is.
  std::filesystem::path path = std::filesystem::path(base_dir) / file;
  if (form == PathForm::kAbsolute) path = std::filesystem::absolute(path);
  return path.lexically_normal().string();
}

YamlReader YamlReader::load_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path, "", "cannot open the file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return load_string(buffer.str(), path);
}

YamlReader YamlReader::load_string(const std::string& text, const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::DeepRecursion& e) {  // its own message says "bad file"
    throw ConfigError(source_name, "", "invalid YAML: nested too deeply (line " + std::to_string(e.mark.line + 1) + ")");
  } catch (const YAML::Exception& e) {
    throw ConfigError(source_name, "", std::string("invalid YAML: ") + e.what());
  }
  DocumentCheck(source_name).check(root, "");
  return YamlReader(std::move(root), source_name, "");
}

YamlReader::YamlReader(YAML::Node node, std::string file, std::string path)
    : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}

std::string YamlReader::path_of(std::string_view key) const {
  if (key.empty()) return path_;
  if (path_.empty()) return std::string(key);
  return path_ + "." + std::string(key);
}

ConfigError YamlReader::error(std::string_view key, const std::string& reason) const {
  return ConfigError(file_, path_of(key), reason);
}

void YamlReader::expect_map() const {
  if (is_null()) return;
  if (!node_.IsMap()) throw error("", "expected a map of keys");
}

void YamlReader::expect_sequence() const {
  if (!node_.IsSequence()) throw error("", "expected a sequence");
}

void YamlReader::allow_keys(std::initializer_list<std::string_view> keys) const {
  expect_map();
  if (is_null()) return;
  for (const auto& item : node_) {
    std::string key;
    try {
      key = item.first.as<std::string>();
    } catch (const YAML::Exception&) {
      throw error("", "keys must be strings");
    }
    bool known = false;
    for (const auto& allowed : keys) known = known || key == allowed;
    if (!known) {
      std::string list;
      for (const auto& allowed : keys) list += (list.empty() ? "" : ", ") + std::string(allowed);
      throw error(key, "unknown key (allowed here: " + list + ")");
    }
  }
}

std::vector<std::string> YamlReader::keys() const {
  expect_map();
  std::vector<std::string> out;
  if (is_null()) return out;
  for (const auto& item : node_) {
    try {
      out.push_back(item.first.as<std::string>());
    } catch (const YAML::Exception&) {
      throw error("", "keys must be strings");
    }
  }
  return out;
}

bool YamlReader::has(std::string_view key) const {
  if (is_null() || !node_.IsMap()) return false;
  const YAML::Node child = node_[std::string(key)];
  return child && !child.IsNull();
}

YamlReader YamlReader::at(std::string_view key) const {
  expect_map();
  if (!has(key)) throw error(key, "missing key");
  return YamlReader(node_[std::string(key)], file_, path_of(key));
}

std::size_t YamlReader::size() const {
  if (is_null()) return 0;
  expect_sequence();
  return node_.size();
}

YamlReader YamlReader::at(std::size_t index) const {
  expect_sequence();
  if (index >= node_.size()) throw error("", "index " + std::to_string(index) + " out of range");
  return YamlReader(node_[index], file_, path_ + "[" + std::to_string(index) + "]");
}

double YamlReader::as_number(double min, double max) const {
  if (is_null() || !node_.IsScalar()) throw error("", "expected a number");
  double value = 0.0;
  try {
    value = node_.as<double>();
  } catch (const YAML::Exception&) {
    throw error("", "expected a number, got '" + node_.Scalar() + "'");
  }
  if (!std::isfinite(value)) throw error("", "must be finite, got '" + node_.Scalar() + "'");
  if (value < min || value > max) {
    throw error("", "must be in " + format_range(min, max, kMessageDigits) + ", got " + format_general(value, kMessageDigits));
  }
  return value;
}

long long YamlReader::as_integer(long long min, long long max) const {
  if (is_null() || !node_.IsScalar()) throw error("", "expected an integer");
  long long value = 0;
  try {
    value = node_.as<long long>();
  } catch (const YAML::Exception&) {
    throw error("", "expected an integer, got '" + node_.Scalar() + "'");
  }
  if (value < min || value > max) {
    throw error("", "must be in [" + std::to_string(min) + ", " + std::to_string(max) + "], got " +
                        std::to_string(value));
  }
  return value;
}

bool YamlReader::as_boolean() const {
  if (is_null() || !node_.IsScalar()) throw error("", "expected true or false");
  const std::string& s = node_.Scalar();
  if (s == "true") return true;
  if (s == "false") return false;
  throw error("", "expected true or false, got '" + s + "'");
}

std::string YamlReader::as_text() const {
  if (is_null() || !node_.IsScalar()) throw error("", "expected a string");
  return node_.Scalar();
}

double YamlReader::number(std::string_view key, double min, double max) const {
  return at(key).as_number(min, max);
}

double YamlReader::number_or(std::string_view key, double fallback, double min, double max) const {
  return has(key) ? number(key, min, max) : fallback;
}

long long YamlReader::integer(std::string_view key, long long min, long long max) const {
  return at(key).as_integer(min, max);
}

long long YamlReader::integer_or(std::string_view key, long long fallback, long long min, long long max) const {
  return has(key) ? integer(key, min, max) : fallback;
}

bool YamlReader::boolean(std::string_view key) const { return at(key).as_boolean(); }

bool YamlReader::boolean_or(std::string_view key, bool fallback) const {
  return has(key) ? boolean(key) : fallback;
}

std::string YamlReader::text(std::string_view key) const { return at(key).as_text(); }

std::string YamlReader::text_or(std::string_view key, const std::string& fallback) const {
  return has(key) ? text(key) : fallback;
}

std::string YamlReader::choice(std::string_view key, std::initializer_list<std::string_view> choices) const {
  const std::string value = text(key);
  std::string list;
  for (const auto& c : choices) {
    if (value == c) return value;
    list += (list.empty() ? "" : ", ") + std::string(c);
  }
  throw error(key, "must be one of " + list + ", got '" + value + "'");
}

std::string YamlReader::choice_or(std::string_view key, const std::string& fallback,
                                  std::initializer_list<std::string_view> choices) const {
  return has(key) ? choice(key, choices) : fallback;
}

std::vector<double> YamlReader::numbers(std::string_view key, int expected_size, double min, double max) const {
  const YamlReader list = at(key);
  if (!list.is_sequence()) throw error(key, "expected a sequence of numbers");
  if (expected_size >= 0 && list.size() != static_cast<std::size_t>(expected_size)) {
    throw error(key, "expected " + std::to_string(expected_size) + " numbers, got " + std::to_string(list.size()));
  }
  std::vector<double> out;
  out.reserve(list.size());
  for (std::size_t i = 0; i < list.size(); ++i) out.push_back(list.at(i).as_number(min, max));
  return out;
}

Eigen::Vector3d YamlReader::vector3(std::string_view key, double min, double max) const {
  const std::vector<double> v = numbers(key, 3, min, max);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

Eigen::Vector3d YamlReader::vector3_or(std::string_view key, const Eigen::Vector3d& fallback, double min,
                                       double max) const {
  return has(key) ? vector3(key, min, max) : fallback;
}

}  // namespace phri
