#include <phri/ros2/dds_config.hpp>

#include <cstdlib>
#include <string>

namespace phri {

int resolve_ros_domain(int configured) {
  if (configured >= 0) return configured;
  const char* env = std::getenv("ROS_DOMAIN_ID");
  if (env == nullptr || *env == '\0') return 0;
  char* end = nullptr;
  const long id = std::strtol(env, &end, 10);
  return (*end == '\0' && id >= 0 && id <= 232) ? static_cast<int>(id) : 0;
}

std::string loopback_cyclone_xml() {
  return "<CycloneDDS><Domain Id=\"any\">"
         "<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast></General>"
         "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
         "<MaxAutoParticipantIndex>" + std::to_string(kLoopbackMaxParticipants - 1) + "</MaxAutoParticipantIndex>"
         "<Peers><Peer Address=\"127.0.0.1\"/></Peers></Discovery>"
         "</Domain></CycloneDDS>";
}

}  // namespace phri
