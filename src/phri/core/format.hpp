#pragma once
// Numbers as text, one definition for tables, CSV files and messages; and text as a number.
#include <optional>
#include <string>

namespace phri {

/// `value` with `digits` decimals, as printf "%.*f" (format_fixed(x, 6) equals std::to_string(x)).
std::string format_fixed(double value, int digits);

/// `value` with up to `significant` significant digits, as printf "%.*g" (format_general(x, 6)
/// equals what `std::ostream << x` writes with the default settings).
std::string format_general(double value, int significant);

/// "[lower, upper]", each with format_general's `significant` digits (messages about ranges).
std::string format_range(double lower, double upper, int significant = 6);

/// The whole of `text` as one number (std::stod's syntax, so "inf" and "nan" too: the caller
/// decides about them); nothing when it is not a number or has anything after it.
std::optional<double> parse_number(const std::string& text);

}  // namespace phri
