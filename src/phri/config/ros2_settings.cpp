#include <phri/config/ros2_settings.hpp>

namespace phri {

bool valid_ros_namespace(const std::string& ns) {
  if (ns.size() < 2 || ns.front() != '/' || ns.back() == '/') return false;
  bool segment_start = true;
  for (std::size_t i = 1; i < ns.size(); ++i) {
    const char ch = ns[i];
    if (ch == '/') {
      if (segment_start) return false;
      segment_start = true;
      continue;
    }
    const bool alpha = (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z') || ch == '_';
    if (!alpha && !(ch >= '0' && ch <= '9')) return false;
    if (segment_start && !alpha) return false;  // a segment starts with a letter or '_'
    segment_start = false;
  }
  return true;
}

}  // namespace phri
