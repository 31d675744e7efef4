// CDR encode/decode of the ROS 2 messages, field by field in .msg order.
#include "ros2/messages.hpp"

namespace faultline::ros2 {

namespace {

// Bytes an element occupies at least (alignment padding not counted): the bound a sequence count is
// checked against before any element is decoded.
constexpr std::size_t kMinTransformStamped = 8 + 4 + 4 + 7 * 8;
constexpr std::size_t kMinKeyValue = 4 + 4;
constexpr std::size_t kMinDiagnosticStatus = 1 + 4 + 4 + 4 + 4;
constexpr std::size_t kMinMarker =
    12 + 4 + 12 + 56 + 24 + 16 + 8 + 1 + 4 + 4 + 4 + (12 + 4 + 4 + 4) + 4 + 4 + 4 + (4 + 4) + 1;

template <typename T>
void encode_sequence(CdrWriter& w, const std::vector<T>& v) {
  w.sequence_count(v.size());
  for (const T& e : v) encode(w, e);
}

// Elements are appended as they decode (no reserve from the count), so memory follows the input's
// size.
template <typename T>
void decode_sequence(CdrReader& r, const char* field, std::size_t min_element_bytes,
                     std::vector<T>& out) {
  out.clear();
  const std::uint32_t n = r.sequence_count(field, min_element_bytes);
  for (std::uint32_t i = 0; i < n && r.ok(); ++i) {
    T e;
    decode(r, e);
    out.push_back(std::move(e));
  }
}

}  // namespace

void encode(CdrWriter& w, const Time& m) {
  w.i32(m.sec);
  w.u32(m.nanosec);
}
void encode(CdrWriter& w, const Duration& m) {
  w.i32(m.sec);
  w.u32(m.nanosec);
}
void encode(CdrWriter& w, const Header& m) {
  encode(w, m.stamp);
  w.string(m.frame_id);
}
void encode(CdrWriter& w, const CompressedImage& m) {
  encode(w, m.header);
  w.string(m.format);
  w.octets(m.data);
}
void encode(CdrWriter& w, const Image& m) {
  encode(w, m.header);
  w.u32(m.height);
  w.u32(m.width);
  w.string(m.encoding);
  w.u8(m.is_bigendian);
  w.u32(m.step);
  w.octets(m.data);
}
void encode(CdrWriter& w, const RegionOfInterest& m) {
  w.u32(m.x_offset);
  w.u32(m.y_offset);
  w.u32(m.height);
  w.u32(m.width);
  w.boolean(m.do_rectify);
}
void encode(CdrWriter& w, const CameraInfo& m) {
  encode(w, m.header);
  w.u32(m.height);
  w.u32(m.width);
  w.string(m.distortion_model);
  w.f64_sequence(m.d.data(), m.d.size());
  w.f64_array(m.k.data(), m.k.size());
  w.f64_array(m.r.data(), m.r.size());
  w.f64_array(m.p.data(), m.p.size());
  w.u32(m.binning_x);
  w.u32(m.binning_y);
  encode(w, m.roi);
}
void encode(CdrWriter& w, const Vector3& m) {
  w.f64(m.x);
  w.f64(m.y);
  w.f64(m.z);
}
void encode(CdrWriter& w, const Quaternion& m) {
  w.f64(m.x);
  w.f64(m.y);
  w.f64(m.z);
  w.f64(m.w);
}
void encode(CdrWriter& w, const Transform& m) {
  encode(w, m.translation);
  encode(w, m.rotation);
}
void encode(CdrWriter& w, const Pose& m) {
  encode(w, m.position);
  encode(w, m.orientation);
}
void encode(CdrWriter& w, const TransformStamped& m) {
  encode(w, m.header);
  w.string(m.child_frame_id);
  encode(w, m.transform);
}
void encode(CdrWriter& w, const TFMessage& m) { encode_sequence(w, m.transforms); }
void encode(CdrWriter& w, const KeyValue& m) {
  w.string(m.key);
  w.string(m.value);
}
void encode(CdrWriter& w, const DiagnosticStatus& m) {
  w.u8(m.level);
  w.string(m.name);
  w.string(m.message);
  w.string(m.hardware_id);
  encode_sequence(w, m.values);
}
void encode(CdrWriter& w, const DiagnosticArray& m) {
  encode(w, m.header);
  encode_sequence(w, m.status);
}
void encode(CdrWriter& w, const ColorRGBA& m) {
  w.f32(m.r);
  w.f32(m.g);
  w.f32(m.b);
  w.f32(m.a);
}
void encode(CdrWriter& w, const UVCoordinate& m) {
  w.f64(m.u);
  w.f64(m.v);
}
void encode(CdrWriter& w, const MeshFile& m) {
  w.string(m.filename);
  w.octets(m.data);
}
void encode(CdrWriter& w, const Marker& m) {
  encode(w, m.header);
  w.string(m.ns);
  w.i32(m.id);
  w.i32(m.type);
  w.i32(m.action);
  encode(w, m.pose);
  encode(w, m.scale);
  encode(w, m.color);
  encode(w, m.lifetime);
  w.boolean(m.frame_locked);
  encode_sequence(w, m.points);
  encode_sequence(w, m.colors);
  w.string(m.texture_resource);
  encode(w, m.texture);
  encode_sequence(w, m.uv_coordinates);
  w.string(m.text);
  w.string(m.mesh_resource);
  encode(w, m.mesh_file);
  w.boolean(m.mesh_use_embedded_materials);
}
void encode(CdrWriter& w, const MarkerArray& m) { encode_sequence(w, m.markers); }

void decode(CdrReader& r, Time& m) {
  m.sec = r.i32("stamp.sec");
  m.nanosec = r.u32("stamp.nanosec");
}
void decode(CdrReader& r, Duration& m) {
  m.sec = r.i32("duration.sec");
  m.nanosec = r.u32("duration.nanosec");
}
void decode(CdrReader& r, Header& m) {
  decode(r, m.stamp);
  m.frame_id = r.string("header.frame_id");
}
void decode(CdrReader& r, CompressedImage& m) {
  decode(r, m.header);
  m.format = r.string("format");
  m.data = r.octets("data");
}
void decode(CdrReader& r, Image& m) {
  decode(r, m.header);
  m.height = r.u32("height");
  m.width = r.u32("width");
  m.encoding = r.string("encoding");
  m.is_bigendian = r.u8("is_bigendian");
  m.step = r.u32("step");
  m.data = r.octets("data");
}
void decode(CdrReader& r, RegionOfInterest& m) {
  m.x_offset = r.u32("roi.x_offset");
  m.y_offset = r.u32("roi.y_offset");
  m.height = r.u32("roi.height");
  m.width = r.u32("roi.width");
  m.do_rectify = r.boolean("roi.do_rectify");
}
void decode(CdrReader& r, CameraInfo& m) {
  decode(r, m.header);
  m.height = r.u32("height");
  m.width = r.u32("width");
  m.distortion_model = r.string("distortion_model");
  m.d.clear();
  const std::uint32_t nd = r.sequence_count("d", 8);
  for (std::uint32_t i = 0; i < nd && r.ok(); ++i) m.d.push_back(r.f64("d"));
  r.f64_array("k", m.k.data(), m.k.size());
  r.f64_array("r", m.r.data(), m.r.size());
  r.f64_array("p", m.p.data(), m.p.size());
  m.binning_x = r.u32("binning_x");
  m.binning_y = r.u32("binning_y");
  decode(r, m.roi);
}
void decode(CdrReader& r, Vector3& m) {
  m.x = r.f64("x");
  m.y = r.f64("y");
  m.z = r.f64("z");
}
void decode(CdrReader& r, Quaternion& m) {
  m.x = r.f64("x");
  m.y = r.f64("y");
  m.z = r.f64("z");
  m.w = r.f64("w");
}
void decode(CdrReader& r, Transform& m) {
  decode(r, m.translation);
  decode(r, m.rotation);
}
void decode(CdrReader& r, Pose& m) {
  decode(r, m.position);
  decode(r, m.orientation);
}
void decode(CdrReader& r, TransformStamped& m) {
  decode(r, m.header);
  m.child_frame_id = r.string("child_frame_id");
  decode(r, m.transform);
}
void decode(CdrReader& r, TFMessage& m) {
  decode_sequence(r, "transforms", kMinTransformStamped, m.transforms);
}
void decode(CdrReader& r, KeyValue& m) {
  m.key = r.string("key");
  m.value = r.string("value");
}
void decode(CdrReader& r, DiagnosticStatus& m) {
  m.level = r.u8("level");
  m.name = r.string("name");
  m.message = r.string("message");
  m.hardware_id = r.string("hardware_id");
  decode_sequence(r, "values", kMinKeyValue, m.values);
}
void decode(CdrReader& r, DiagnosticArray& m) {
  decode(r, m.header);
  decode_sequence(r, "status", kMinDiagnosticStatus, m.status);
}
void decode(CdrReader& r, ColorRGBA& m) {
  m.r = r.f32("r");
  m.g = r.f32("g");
  m.b = r.f32("b");
  m.a = r.f32("a");
}
void decode(CdrReader& r, UVCoordinate& m) {
  m.u = r.f64("u");
  m.v = r.f64("v");
}
void decode(CdrReader& r, MeshFile& m) {
  m.filename = r.string("mesh_file.filename");
  m.data = r.octets("mesh_file.data");
}
void decode(CdrReader& r, Marker& m) {
  decode(r, m.header);
  m.ns = r.string("ns");
  m.id = r.i32("id");
  m.type = r.i32("type");
  m.action = r.i32("action");
  decode(r, m.pose);
  decode(r, m.scale);
  decode(r, m.color);
  decode(r, m.lifetime);
  m.frame_locked = r.boolean("frame_locked");
  decode_sequence(r, "points", 24, m.points);
  decode_sequence(r, "colors", 16, m.colors);
  m.texture_resource = r.string("texture_resource");
  decode(r, m.texture);
  decode_sequence(r, "uv_coordinates", 16, m.uv_coordinates);
  m.text = r.string("text");
  m.mesh_resource = r.string("mesh_resource");
  decode(r, m.mesh_file);
  m.mesh_use_embedded_materials = r.boolean("mesh_use_embedded_materials");
}
void decode(CdrReader& r, MarkerArray& m) { decode_sequence(r, "markers", kMinMarker, m.markers); }

std::string compressed_image_prefix(const Header& header, std::string_view format,
                                    std::size_t data_bytes) {
  CdrWriter w;
  encode(w, header);
  w.string(format);
  w.sequence_count(data_bytes);
  return w.take();
}

Time time_from_us(std::int64_t us) {
  std::int64_t sec = us / 1'000'000;
  std::int64_t rem = us % 1'000'000;
  if (rem < 0) {
    rem += 1'000'000;
    sec -= 1;
  }
  return Time{static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(rem * 1000)};
}

Time time_from_ns(StampNs ns) {
  std::int64_t sec = ns / kNsPerSec;
  std::int64_t rem = ns % kNsPerSec;
  if (rem < 0) {
    rem += kNsPerSec;
    sec -= 1;
  }
  return Time{static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(rem)};
}

StampNs to_ns(const Time& t) {
  return static_cast<StampNs>(t.sec) * kNsPerSec + static_cast<StampNs>(t.nanosec);
}

Status set_header_stamp(std::string& message, const Time& stamp) {
  constexpr std::size_t kStampEnd = kEncapsulationBytes + 8;
  if (message.size() < kStampEnd) {
    return Status(StatusCode::kTruncated,
                  "message of " + std::to_string(message.size()) + " bytes has no header stamp");
  }
  // The representation id (the first two bytes) says CDR_LE; the options bytes may be anything.
  if (message[0] != '\x00' || message[1] != '\x01') {
    return Status(StatusCode::kCorruptData, "header stamp: the message is not CDR_LE");
  }
  const auto sec = static_cast<std::uint32_t>(stamp.sec);
  for (std::size_t i = 0; i < 4; ++i) {
    message[kEncapsulationBytes + i] = static_cast<char>((sec >> (8 * i)) & 0xFF);
    message[kEncapsulationBytes + 4 + i] = static_cast<char>((stamp.nanosec >> (8 * i)) & 0xFF);
  }
  return Status::ok();
}

CameraInfo camera_info_from_k(const Header& header, std::uint32_t width, std::uint32_t height,
                              const std::array<double, 9>& k) {
  CameraInfo info;
  info.header = header;
  info.width = width;
  info.height = height;
  info.distortion_model = "plumb_bob";
  info.d.assign(5, 0.0);
  info.k = k;
  info.r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (std::size_t row = 0; row < 3; ++row) {
    for (std::size_t col = 0; col < 3; ++col) info.p[row * 4 + col] = k[row * 3 + col];
    info.p[row * 4 + 3] = 0.0;
  }
  return info;
}

}  // namespace faultline::ros2
