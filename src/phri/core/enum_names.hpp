#pragma once
// The inverse of an enumeration's to_string, for enumerations whose values are 0 .. Count - 1:
// each enumeration writes its names once (its to_string) and parses with this.
#include <optional>
#include <string_view>

namespace phri {

template <class Enum, int Count>
constexpr std::optional<Enum> enum_from_string(std::string_view name) {
  for (int i = 0; i < Count; ++i) {
    if (to_string(static_cast<Enum>(i)) == name) return static_cast<Enum>(i);
  }
  return std::nullopt;
}

}  // namespace phri
