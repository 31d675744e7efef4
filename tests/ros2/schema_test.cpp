// ros2msg definitions: the exact text for a small type, and the rosbag2 order and uniqueness of
// dependencies.
#include "ros2/schema.hpp"

#include <gtest/gtest.h>

#include <string>

#include "ros2/messages.hpp"

namespace faultline::ros2 {
namespace {

const std::string kRule(80, '=');

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

TEST(SchemaTest, CompressedImageExactText) {
  auto def = ros2msg_definition(MessageTraits<CompressedImage>::kTypeName);
  ASSERT_TRUE(def.is_ok());
  EXPECT_EQ(*def,
            "std_msgs/Header header\nstring format\nuint8[] data\n"
            "\n" +
                kRule +
                "\nMSG: std_msgs/Header\n"
                "builtin_interfaces/Time stamp\nstring frame_id\n"
                "\n" +
                kRule +
                "\nMSG: builtin_interfaces/Time\n"
                "int32 sec\nuint32 nanosec\n");
}

TEST(SchemaTest, DependenciesDepthFirstInSortedOrder) {
  auto def = ros2msg_definition("sensor_msgs/msg/CameraInfo");
  ASSERT_TRUE(def.is_ok());
  const auto roi = def->find("MSG: sensor_msgs/RegionOfInterest\n");
  const auto header = def->find("MSG: std_msgs/Header\n");
  const auto time = def->find("MSG: builtin_interfaces/Time\n");
  ASSERT_NE(roi, std::string::npos);
  ASSERT_NE(header, std::string::npos);
  ASSERT_NE(time, std::string::npos);
  EXPECT_LT(roi, header);   // "sensor_msgs/..." sorts before "std_msgs/..."
  EXPECT_LT(header, time);  // Time is Header's dependency, written right after it
  EXPECT_EQ(def->rfind("std_msgs/Header header\n", 0), 0u);
}

TEST(SchemaTest, EachDependencyOnce) {
  auto def = ros2msg_definition("visualization_msgs/msg/MarkerArray");
  ASSERT_TRUE(def.is_ok());
  for (const char* dep :
       {"visualization_msgs/Marker", "std_msgs/Header", "builtin_interfaces/Time",
        "builtin_interfaces/Duration", "geometry_msgs/Pose", "geometry_msgs/Point",
        "geometry_msgs/Quaternion", "geometry_msgs/Vector3", "std_msgs/ColorRGBA",
        "sensor_msgs/CompressedImage", "visualization_msgs/UVCoordinate",
        "visualization_msgs/MeshFile"}) {
    EXPECT_EQ(count_of(*def, std::string("MSG: ") + dep + "\n"), 1u) << dep;
  }
  EXPECT_EQ(count_of(*def, kRule), 12u);
  auto tf = ros2msg_definition("tf2_msgs/msg/TFMessage");
  ASSERT_TRUE(tf.is_ok());
  for (const char* dep :
       {"geometry_msgs/TransformStamped", "geometry_msgs/Transform", "geometry_msgs/Vector3",
        "geometry_msgs/Quaternion", "std_msgs/Header", "builtin_interfaces/Time"}) {
    EXPECT_EQ(count_of(*tf, std::string("MSG: ") + dep + "\n"), 1u) << dep;
  }
  auto diag = ros2msg_definition("diagnostic_msgs/msg/DiagnosticArray");
  ASSERT_TRUE(diag.is_ok());
  EXPECT_EQ(count_of(*diag, "MSG: diagnostic_msgs/KeyValue\n"), 1u);
  EXPECT_EQ(count_of(*diag, "MSG: diagnostic_msgs/DiagnosticStatus\n"), 1u);
}

TEST(SchemaTest, EveryTopLevelTypeHasADefinition) {
  for (const char* t :
       {MessageTraits<CompressedImage>::kTypeName, MessageTraits<Image>::kTypeName,
        MessageTraits<CameraInfo>::kTypeName, MessageTraits<TFMessage>::kTypeName,
        MessageTraits<DiagnosticArray>::kTypeName, MessageTraits<MarkerArray>::kTypeName,
        MessageTraits<TransformStamped>::kTypeName}) {
    EXPECT_TRUE(ros2msg_definition(t).is_ok()) << t;
  }
  EXPECT_EQ(known_types().size(), 22u);
}

TEST(SchemaTest, UnknownTypeIsNotFound) {
  auto def = ros2msg_definition("sensor_msgs/msg/PointCloud2");
  ASSERT_FALSE(def.is_ok());
  EXPECT_EQ(def.status().code(), StatusCode::kNotFound);
  EXPECT_NE(def.status().message().find("sensor_msgs/msg/PointCloud2"), std::string::npos);
  EXPECT_FALSE(ros2msg_definition("sensor_msgs/srv/CameraInfo").is_ok());
  EXPECT_FALSE(ros2msg_definition("CameraInfo").is_ok());
}

}  // namespace
}  // namespace faultline::ros2
