#pragma once
// Cyclone DDS configuration for the bridge: the domain id (ROS_DOMAIN_ID convention) and the
// discovery that works where phri runs. "loopback": unicast to 127.0.0.1 only, no multicast
// (a loopback interface usually has no MULTICAST flag), participant indices 0..kMaxParticipants-1
// so that unicast discovery knows every port; "network": Cyclone's defaults (multicast on the
// machine's interfaces) or the user's CYCLONEDDS_URI. docs/ros2.md shows both files.
#include <string>

namespace phri {

inline constexpr int kLoopbackMaxParticipants = 20;

/// The DDS domain: `configured` if >= 0, else $ROS_DOMAIN_ID if it is a number in [0, 232], else 0.
int resolve_ros_domain(int configured);

/// Cyclone's XML for discovery over loopback without multicast (the `Domain` element matches any id).
std::string loopback_cyclone_xml();

}  // namespace phri
