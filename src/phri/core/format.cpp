#include <phri/core/format.hpp>

#include <cstdio>
#include <exception>

namespace phri {
namespace {
// printf of one double with "%.*f" (fixed) or "%.*g"; literal formats keep -Wformat's checks.
int print(char* buffer, std::size_t size, bool fixed, int precision, double value) {
  return fixed ? std::snprintf(buffer, size, "%.*f", precision, value)
               : std::snprintf(buffer, size, "%.*g", precision, value);
}

std::string format(bool fixed, int precision, double value) {
  char buffer[128];
  const int n = print(buffer, sizeof(buffer), fixed, precision, value);
  if (n < 0) return {};
  if (static_cast<std::size_t>(n) < sizeof(buffer)) return std::string(buffer, static_cast<std::size_t>(n));
  std::string text(static_cast<std::size_t>(n) + 1, '\0');  // e.g. %.2f of 1e300
  print(text.data(), text.size(), fixed, precision, value);
  text.resize(static_cast<std::size_t>(n));
  return text;
}
}  // namespace

std::string format_fixed(double value, int digits) { return format(true, digits, value); }

std::string format_general(double value, int significant) { return format(false, significant, value); }

std::string format_range(double lower, double upper, int significant) {
  std::string text = "[";  // appended piece by piece: GCC 12's -Wrestrict misfires on "[" + std::string
  text += format_general(lower, significant);
  text += ", ";
  text += format_general(upper, significant);
  text += "]";
  return text;
}

std::optional<double> parse_number(const std::string& text) {
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != text.size()) return std::nullopt;
  return value;
}

}  // namespace phri
