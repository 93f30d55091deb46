#include <phri/core/number_text.hpp>

#include <cstdio>

namespace phri {

std::string format_number(double value, int significant_digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*g", significant_digits, value);
  return buffer;
}

}  // namespace phri
