#include <phri/core/version.hpp>
namespace phri {
const char* version() { return PHRI_VERSION; }
}  // namespace phri
