#include <phri/app/backend_registry.hpp>

#include <phri/core/error.hpp>

#include <utility>

namespace phri {

void BackendRegistry::add(const std::string& name, BackendFactory factory) { factories_[name] = std::move(factory); }

std::vector<std::string> BackendRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [name, factory] : factories_) out.push_back(name);
  return out;
}

void BackendRegistry::require(const std::string& name) const {
  if (has(name)) return;
  std::string known;
  for (const auto& [known_name, factory] : factories_) known += (known.empty() ? "" : ", ") + known_name;
  throw ConfigError("--backend", name, "unknown backend (known: " + known + ")");
}

std::unique_ptr<Backend> BackendRegistry::make(const std::string& name, const BackendRequest& request) const {
  require(name);
  return factories_.at(name)(request);
}

}  // namespace phri
