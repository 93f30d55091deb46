#pragma once
namespace phri {
/// Library version, "major.minor.patch".
const char* version();
}  // namespace phri
