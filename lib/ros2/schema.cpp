// The .msg texts Faultline writes and the rosbag2-style assembly of a complete definition.
#include "ros2/schema.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <set>

namespace faultline::ros2 {

namespace {

// "pkg/Type" -> .msg text (field and constant lines, ros2/common_interfaces Humble, comments left
// out). The wire layout of every type here is the same in Jazzy (whose Marker only adds the
// ARROW_STRIP constant).
const std::map<std::string, std::string, std::less<>>& msg_texts() {
  static const std::map<std::string, std::string, std::less<>> kTexts = {
      {"builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"},
      {"builtin_interfaces/Duration", "int32 sec\nuint32 nanosec\n"},
      {"std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"},
      {"std_msgs/ColorRGBA", "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n"},
      {"sensor_msgs/CompressedImage", "std_msgs/Header header\nstring format\nuint8[] data\n"},
      {"sensor_msgs/Image",
       "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 "
       "is_bigendian\nuint32 step\n"
       "uint8[] data\n"},
      {"sensor_msgs/RegionOfInterest",
       "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n"},
      {"sensor_msgs/CameraInfo",
       "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] "
       "d\nfloat64[9] k\n"
       "float64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\nRegionOfInterest roi\n"},
      {"geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"},
      {"geometry_msgs/Pose", "Point position\nQuaternion orientation\n"},
      {"geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation\n"},
      {"geometry_msgs/TransformStamped",
       "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"},
      {"tf2_msgs/TFMessage", "geometry_msgs/TransformStamped[] transforms\n"},
      {"diagnostic_msgs/KeyValue", "string key\nstring value\n"},
      {"diagnostic_msgs/DiagnosticStatus",
       "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\n\nbyte level\nstring name\nstring "
       "message\n"
       "string hardware_id\nKeyValue[] values\n"},
      {"diagnostic_msgs/DiagnosticArray", "std_msgs/Header header\nDiagnosticStatus[] status\n"},
      {"visualization_msgs/Marker",
       "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\nint32 "
       "LINE_LIST=5\n"
       "int32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\nint32 TEXT_VIEW_FACING=9\nint32 "
       "MESH_RESOURCE=10\n"
       "int32 TRIANGLE_LIST=11\n\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 "
       "DELETEALL=3\n\n"
       "std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\ngeometry_msgs/Pose "
       "pose\n"
       "geometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\nbuiltin_interfaces/Duration "
       "lifetime\n"
       "bool frame_locked\n\ngeometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\n\n"
       "string texture_resource\nsensor_msgs/CompressedImage texture\nUVCoordinate[] "
       "uv_coordinates\n\n"
       "string text\n\nstring mesh_resource\nMeshFile mesh_file\nbool "
       "mesh_use_embedded_materials\n"},
      {"visualization_msgs/UVCoordinate", "float64 u\nfloat64 v\n"},
      {"visualization_msgs/MeshFile", "string filename\nuint8[] data\n"},
      {"visualization_msgs/MarkerArray", "Marker[] markers\n"},
  };
  return kTexts;
}

bool is_primitive(std::string_view t) {
  static const std::set<std::string_view> kPrimitives = {
      "bool",   "byte",  "char",   "float32", "float64", "int8",   "uint8",  "int16",
      "uint16", "int32", "uint32", "int64",   "uint64",  "string", "wstring"};
  return kPrimitives.count(t) != 0;
}

// "pkg/msg/Type" or "pkg/Type" -> "pkg/Type"; "" when neither.
std::string short_name(std::string_view type_name) {
  const auto first = type_name.find('/');
  if (first == std::string_view::npos || first == 0) return {};
  const auto last = type_name.rfind('/');
  if (last == first) return std::string(type_name);
  if (type_name.substr(first, last - first + 1) != "/msg/") return {};
  return std::string(type_name.substr(0, first)) + std::string(type_name.substr(last));
}

// The complex field types of a .msg text, as "pkg/Type", sorted and unique.
std::set<std::string> dependencies(std::string_view text, std::string_view package) {
  std::set<std::string> out;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    const auto start = line.find_first_not_of(" \t");
    if (start == std::string_view::npos || line[start] == '#') continue;
    line.remove_prefix(start);
    std::string_view type = line.substr(0, line.find_first_of(" \t"));
    type = type.substr(0, type.find('['));
    type = type.substr(0, type.find('<'));  // bounded strings: string<=5
    if (type.empty() || is_primitive(type)) continue;
    if (type.find('/') == std::string_view::npos) {
      out.insert(std::string(package) + "/" + std::string(type));
    } else {
      out.insert(std::string(type));
    }
  }
  return out;
}

}  // namespace

std::string_view msg_text(std::string_view type_name) {
  const auto& texts = msg_texts();
  const auto it = texts.find(short_name(type_name));
  return it == texts.end() ? std::string_view() : std::string_view(it->second);
}

Result<std::string> ros2msg_definition(std::string_view type_name) {
  const std::string root = short_name(type_name);
  if (msg_text(root).empty()) {
    return Status(StatusCode::kNotFound,
                  "no ros2msg definition for type \"" + std::string(type_name) + "\"");
  }
  std::set<std::string> seen;
  std::string missing;
  std::function<std::string(const std::string&)> append = [&](const std::string& name) {
    const std::string_view text = msg_text(name);
    std::string out(text);
    for (const std::string& dep : dependencies(text, name.substr(0, name.find('/')))) {
      if (!seen.insert(dep).second) continue;
      if (msg_text(dep).empty()) {
        missing = dep;
        continue;
      }
      out += "\n" + std::string(80, '=') + "\nMSG: " + dep + "\n";
      out += append(dep);
    }
    return out;
  };
  std::string full = append(root);
  if (!missing.empty()) {
    return Status(StatusCode::kInternal,
                  "ros2msg definition of " + root + ": dependency " + missing + " unknown");
  }
  return full;
}

std::vector<std::string> known_types() {
  std::vector<std::string> out;
  for (const auto& [name, text] : msg_texts()) {
    const auto slash = name.find('/');
    out.push_back(name.substr(0, slash) + "/msg" + name.substr(slash));
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace faultline::ros2
