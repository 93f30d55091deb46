#pragma once
// phri::format_number: a double as printf's %g text, for messages and generated files.
#include <string>

namespace phri {

/// `value` with `significant_digits` significant digits (%g): 17 writes a double back exactly
/// (generated MJCF), 10 reads well in error messages.
std::string format_number(double value, int significant_digits);

}  // namespace phri
