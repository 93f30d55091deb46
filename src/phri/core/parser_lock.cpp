#include <phri/core/parser_lock.hpp>

namespace phri {

std::mutex& urdf_parser_mutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace phri
