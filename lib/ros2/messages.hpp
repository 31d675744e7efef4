// ROS 2 messages Faultline writes and reads (field order = wire order, ros2/common_interfaces,
// Humble), with their CDR encoding. serialize(m) gives the bytes a ROS 2 publisher puts on the wire
// and rosbag2 stores (encapsulation header + body); deserialize<M>(bytes) checks every length and
// names the field that failed.
//
//   auto bytes = ros2::serialize(info);                         // std::string, CDR_LE
//   auto back = ros2::deserialize<ros2::CameraInfo>(bytes);     // Result<CameraInfo>
//   ros2::MessageTraits<ros2::CameraInfo>::kTypeName            // "sensor_msgs/msg/CameraInfo"
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/clock.hpp"
#include "common/status.hpp"
#include "ros2/cdr.hpp"

namespace faultline::ros2 {

// builtin_interfaces/Time and /Duration.
struct Time {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;  // 0 .. 999'999'999
};
struct Duration {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
};

struct Header {  // std_msgs/Header
  Time stamp;
  std::string frame_id;
};

struct CompressedImage {  // sensor_msgs/CompressedImage
  Header header;
  std::string format;  // "jpeg", or e.g. "bgr8; jpeg compressed bgr8"
  std::string data;    // the compressed bytes
};

struct Image {  // sensor_msgs/Image
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string encoding;  // "bgr8", "rgb8", "mono8", ...
  std::uint8_t is_bigendian = 0;
  std::uint32_t step = 0;  // bytes per row
  std::string data;        // height * step bytes
};

struct RegionOfInterest {  // sensor_msgs/RegionOfInterest
  std::uint32_t x_offset = 0, y_offset = 0, height = 0, width = 0;
  bool do_rectify = false;
};

struct CameraInfo {  // sensor_msgs/CameraInfo
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string distortion_model;
  std::vector<double> d;
  std::array<double, 9> k{};  // row-major 3x3
  std::array<double, 9> r{};
  std::array<double, 12> p{};  // row-major 3x4
  std::uint32_t binning_x = 0, binning_y = 0;
  RegionOfInterest roi;
};

struct Vector3 {  // geometry_msgs/Vector3 (also the layout of geometry_msgs/Point)
  double x = 0, y = 0, z = 0;
};
using Point = Vector3;
struct Quaternion {  // geometry_msgs/Quaternion
  double x = 0, y = 0, z = 0, w = 1;
};
struct Transform {  // geometry_msgs/Transform
  Vector3 translation;
  Quaternion rotation;
};
struct Pose {  // geometry_msgs/Pose
  Point position;
  Quaternion orientation;
};
struct TransformStamped {  // geometry_msgs/TransformStamped
  Header header;           // frame_id = parent frame
  std::string child_frame_id;
  Transform transform;
};
struct TFMessage {  // tf2_msgs/TFMessage
  std::vector<TransformStamped> transforms;
};

struct KeyValue {  // diagnostic_msgs/KeyValue
  std::string key, value;
};
struct DiagnosticStatus {  // diagnostic_msgs/DiagnosticStatus
  static constexpr std::uint8_t kOk = 0, kWarn = 1, kError = 2, kStale = 3;
  std::uint8_t level = kOk;
  std::string name, message, hardware_id;
  std::vector<KeyValue> values;
};
struct DiagnosticArray {  // diagnostic_msgs/DiagnosticArray
  Header header;
  std::vector<DiagnosticStatus> status;
};

struct ColorRGBA {  // std_msgs/ColorRGBA
  float r = 0, g = 0, b = 0, a = 0;
};
struct UVCoordinate {  // visualization_msgs/UVCoordinate
  double u = 0, v = 0;
};
struct MeshFile {  // visualization_msgs/MeshFile
  std::string filename;
  std::string data;
};
// visualization_msgs/Marker as Humble and Jazzy define it (the texture, uv_coordinates and
// mesh_file fields came with Humble; Jazzy only adds the ARROW_STRIP constant, so the wire layout
// is the same).
struct Marker {
  static constexpr std::int32_t kCube = 1, kAdd = 0, kDeleteAll = 3;
  Header header;
  std::string ns;
  std::int32_t id = 0, type = kCube, action = kAdd;
  Pose pose;
  Vector3 scale;
  ColorRGBA color;
  Duration lifetime;  // 0 = forever
  bool frame_locked = false;
  std::vector<Point> points;
  std::vector<ColorRGBA> colors;
  std::string texture_resource;
  CompressedImage texture;
  std::vector<UVCoordinate> uv_coordinates;
  std::string text, mesh_resource;
  MeshFile mesh_file;
  bool mesh_use_embedded_materials = false;
};
struct MarkerArray {  // visualization_msgs/MarkerArray
  std::vector<Marker> markers;
};

// The ROS 2 type name of each top-level message ("pkg/msg/Type"): MCAP schema name, rosbag2 topic
// type.
template <typename M>
struct MessageTraits;
#define FAULTLINE_ROS2_TYPE(M, NAME)               \
  template <>                                      \
  struct MessageTraits<M> {                        \
    static constexpr const char* kTypeName = NAME; \
  }
FAULTLINE_ROS2_TYPE(Time, "builtin_interfaces/msg/Time");
FAULTLINE_ROS2_TYPE(Header, "std_msgs/msg/Header");
FAULTLINE_ROS2_TYPE(CompressedImage, "sensor_msgs/msg/CompressedImage");
FAULTLINE_ROS2_TYPE(Image, "sensor_msgs/msg/Image");
FAULTLINE_ROS2_TYPE(CameraInfo, "sensor_msgs/msg/CameraInfo");
FAULTLINE_ROS2_TYPE(TransformStamped, "geometry_msgs/msg/TransformStamped");
FAULTLINE_ROS2_TYPE(TFMessage, "tf2_msgs/msg/TFMessage");
FAULTLINE_ROS2_TYPE(DiagnosticArray, "diagnostic_msgs/msg/DiagnosticArray");
FAULTLINE_ROS2_TYPE(MarkerArray, "visualization_msgs/msg/MarkerArray");
#undef FAULTLINE_ROS2_TYPE

// Body encoders (no encapsulation header): nested types and sequences use these.
void encode(CdrWriter& w, const Time& m);
void encode(CdrWriter& w, const Duration& m);
void encode(CdrWriter& w, const Header& m);
void encode(CdrWriter& w, const CompressedImage& m);
void encode(CdrWriter& w, const Image& m);
void encode(CdrWriter& w, const RegionOfInterest& m);
void encode(CdrWriter& w, const CameraInfo& m);
void encode(CdrWriter& w, const Vector3& m);
void encode(CdrWriter& w, const Quaternion& m);
void encode(CdrWriter& w, const Transform& m);
void encode(CdrWriter& w, const Pose& m);
void encode(CdrWriter& w, const TransformStamped& m);
void encode(CdrWriter& w, const TFMessage& m);
void encode(CdrWriter& w, const KeyValue& m);
void encode(CdrWriter& w, const DiagnosticStatus& m);
void encode(CdrWriter& w, const DiagnosticArray& m);
void encode(CdrWriter& w, const ColorRGBA& m);
void encode(CdrWriter& w, const UVCoordinate& m);
void encode(CdrWriter& w, const MeshFile& m);
void encode(CdrWriter& w, const Marker& m);
void encode(CdrWriter& w, const MarkerArray& m);

// Body decoders; failures stay in the reader (r.status()).
void decode(CdrReader& r, Time& m);
void decode(CdrReader& r, Duration& m);
void decode(CdrReader& r, Header& m);
void decode(CdrReader& r, CompressedImage& m);
void decode(CdrReader& r, Image& m);
void decode(CdrReader& r, RegionOfInterest& m);
void decode(CdrReader& r, CameraInfo& m);
void decode(CdrReader& r, Vector3& m);
void decode(CdrReader& r, Quaternion& m);
void decode(CdrReader& r, Transform& m);
void decode(CdrReader& r, Pose& m);
void decode(CdrReader& r, TransformStamped& m);
void decode(CdrReader& r, TFMessage& m);
void decode(CdrReader& r, KeyValue& m);
void decode(CdrReader& r, DiagnosticStatus& m);
void decode(CdrReader& r, DiagnosticArray& m);
void decode(CdrReader& r, ColorRGBA& m);
void decode(CdrReader& r, UVCoordinate& m);
void decode(CdrReader& r, MeshFile& m);
void decode(CdrReader& r, Marker& m);
void decode(CdrReader& r, MarkerArray& m);

// Encapsulation header + body.
template <typename M>
std::string serialize(const M& m) {
  CdrWriter w;
  encode(w, m);
  return w.take();
}

// Errors: kTruncated / kCorruptData naming the type, field and byte; kUnsupported for a non-CDR_LE
// header.
template <typename M>
Result<M> deserialize(std::string_view bytes) {
  CdrReader r(bytes, MessageTraits<M>::kTypeName);
  M m;
  decode(r, m);
  if (!r.ok()) return r.status();
  return m;
}

// A CompressedImage without its data: the encapsulation header and every byte up to and including
// the data count, so that `prefix + data` is the whole message (lets a writer hand the JPEG over
// without a copy).
std::string compressed_image_prefix(const Header& header, std::string_view format,
                                    std::size_t data_bytes);

// nuScenes microsecond stamps: sec = us / 1e6, nanosec = (us % 1e6) * 1000 (floored for negative
// stamps).
Time time_from_us(std::int64_t us);
Time time_from_ns(StampNs ns);
StampNs to_ns(const Time& t);

// Rewrites the header stamp of a serialized message whose first field is a std_msgs/Header
// (CompressedImage, Image, CameraInfo, ...) in place: sec and nanosec are the first 8 bytes of the
// CDR_LE body, and every other byte is kept. kTruncated when shorter than that, kCorruptData when
// the encapsulation is not CDR_LE.
Status set_header_stamp(std::string& message, const Time& stamp);

// A rectified camera's CameraInfo from its 3x3 intrinsics K (row-major): distortion "plumb_bob"
// with five zero coefficients, R = identity, P = [K | 0], no binning, empty ROI.
CameraInfo camera_info_from_k(const Header& header, std::uint32_t width, std::uint32_t height,
                              const std::array<double, 9>& k);

}  // namespace faultline::ros2
