// The `ros2msg` schema text rosbag2 stores for a type (MCAP schema encoding "ros2msg", rosbag2
// docs/message_definition_encoding.md): the type's .msg text, then every type it depends on, each
// once, introduced by a line of 80 '=' and a line `MSG: pkg/Type`. Dependencies are visited depth
// first in sorted order, as rosbag2's LocalMessageDefinitionSource does, so a reader that resolves
// nested types by name finds them all. The .msg texts are the field and constant lines of
// ros2/common_interfaces (Humble; the wire layouts are Jazzy's too), without comments.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "common/status.hpp"

namespace faultline::ros2 {

// The complete definition of `type_name` ("sensor_msgs/msg/CameraInfo" or
// "sensor_msgs/CameraInfo"). kNotFound naming the type when Faultline does not know it.
Result<std::string> ros2msg_definition(std::string_view type_name);

// The .msg text of one known type, without its dependencies; "" when unknown.
std::string_view msg_text(std::string_view type_name);

// Every type ros2msg_definition() knows, as "pkg/msg/Type", sorted.
std::vector<std::string> known_types();

}  // namespace faultline::ros2
