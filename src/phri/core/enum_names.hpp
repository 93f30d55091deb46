#pragma once
// Names of enumerations whose values are 0 .. Count - 1: each writes its names once, as an array
// its to_string reads with enum_name, and parses them back with enum_from_string.
#include <array>
#include <cstddef>
#include <optional>
#include <string_view>

namespace phri {

/// names[value], or `fallback` for a value outside the enumeration.
template <class Enum, std::size_t Count>
constexpr std::string_view enum_name(Enum value, const std::array<std::string_view, Count>& names,
                                     std::string_view fallback = "unknown") {
  const auto i = static_cast<std::size_t>(value);
  return i < Count ? names[i] : fallback;
}

template <class Enum, int Count>
constexpr std::optional<Enum> enum_from_string(std::string_view name) {
  for (int i = 0; i < Count; ++i) {
    if (to_string(static_cast<Enum>(i)) == name) return static_cast<Enum>(i);
  }
  return std::nullopt;
}

}  // namespace phri
