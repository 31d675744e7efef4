// CDR_LE layouts checked byte by byte against hand-computed offsets, round trips of every message,
// and malformed input (truncation, lying counts, wrong encapsulation) reported as errors naming the
// field.
#include "ros2/cdr.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>

#include "ros2/messages.hpp"

namespace faultline::ros2 {
namespace {

std::string bytes(std::initializer_list<int> v) {
  std::string out;
  for (int b : v) out.push_back(static_cast<char>(b));
  return out;
}

double f64_at(const std::string& s, std::size_t offset) {
  double v = 0;
  std::memcpy(&v, s.data() + offset, 8);
  return v;
}

// Built field by field: GCC 12 reports -Wmaybe-uninitialized (falsely) for nested brace-initialised
// strings.
Header header(std::int32_t sec, std::uint32_t nanosec, const char* frame_id) {
  Header h;
  h.stamp.sec = sec;
  h.stamp.nanosec = nanosec;
  h.frame_id = frame_id;
  return h;
}

CompressedImage jpeg_image(Header h, std::string data) {
  CompressedImage img;
  img.header = std::move(h);
  img.format = "jpeg";
  img.data = std::move(data);
  return img;
}

TransformStamped transform(Header h, const char* child, Vector3 t, Quaternion q) {
  TransformStamped out;
  out.header = std::move(h);
  out.child_frame_id = child;
  out.transform.translation = t;
  out.transform.rotation = q;
  return out;
}

std::uint32_t u32_at(const std::string& s, std::size_t offset) {
  std::uint32_t v = 0;
  std::memcpy(&v, s.data() + offset, 4);
  return v;
}

TEST(CdrWriterTest, HeaderStringLayout) {
  EXPECT_EQ(serialize(header(1, 2, "ab")), bytes({0x00, 0x01, 0x00, 0x00,  // CDR_LE encapsulation
                                                  0x01, 0x00, 0x00, 0x00,  // sec
                                                  0x02, 0x00, 0x00, 0x00,  // nanosec
                                                  0x03, 0x00, 0x00, 0x00,  // length with NUL
                                                  'a', 'b', 0x00}));
}

TEST(CdrWriterTest, Float64AfterStringAlignsToEightFromBodyStart) {
  CdrWriter w;
  w.string("abcd");  // body 0..3 length 5, 4..8 "abcd\0"
  w.f64(1.5);        // body 9..15 padding, 16..23 the double
  const std::string& s = w.data();
  ASSERT_EQ(s.size(), 4u + 24u);
  EXPECT_EQ(u32_at(s, 4), 5u);
  EXPECT_EQ(s.substr(8, 5), std::string("abcd\0", 5));
  EXPECT_EQ(s.substr(13, 7), std::string(7, '\0'));
  EXPECT_EQ(f64_at(s, 20), 1.5);
}

TEST(CdrWriterTest, TransformStampedLayout) {
  TransformStamped t;
  t.header = {{1, 0}, "map"};
  t.child_frame_id = "base_link";
  t.transform.translation = {1, 2, 3};
  t.transform.rotation = {0, 0, 0, 1};
  const std::string s = serialize(t);
  // body: 0..7 stamp, 8..11 len 4, 12..15 "map\0", 16..19 len 10, 20..29 "base_link\0", 30..31 pad,
  // 32..55 translation, 56..87 rotation.
  ASSERT_EQ(s.size(), 4u + 88u);
  EXPECT_EQ(u32_at(s, 4 + 16), 10u);
  EXPECT_EQ(s.substr(4 + 20, 10), std::string("base_link\0", 10));
  EXPECT_EQ(s.substr(4 + 30, 2), std::string(2, '\0'));
  EXPECT_EQ(f64_at(s, 4 + 32), 1.0);
  EXPECT_EQ(f64_at(s, 4 + 48), 3.0);
  EXPECT_EQ(f64_at(s, 4 + 80), 1.0);  // w
}

TEST(CdrWriterTest, CameraInfoLayout) {
  const CameraInfo info =
      camera_info_from_k({{0, 0}, "cam"}, 1600, 900, {1, 0, 2, 0, 3, 4, 0, 0, 1});
  const std::string s = serialize(info);
  // body: 0..7 stamp, 8..11 len 4, 12..15 "cam\0", 16 height, 20 width, 24 len 10, 28..37
  // "plumb_bob\0", 38..39 pad, 40 d count, 44..47 pad (float64 elements align to 8), 48..87 d, 88
  // k, 160 r, 232 p, 328 binning_x, 332 binning_y, 336..351 roi offsets/sizes, 352 do_rectify.
  ASSERT_EQ(s.size(), 4u + 353u);
  EXPECT_EQ(u32_at(s, 4 + 16), 900u);
  EXPECT_EQ(u32_at(s, 4 + 20), 1600u);
  EXPECT_EQ(u32_at(s, 4 + 24), 10u);
  EXPECT_EQ(u32_at(s, 4 + 40), 5u);
  EXPECT_EQ(u32_at(s, 4 + 44), 0u);
  EXPECT_EQ(f64_at(s, 4 + 88), 1.0);        // k[0]
  EXPECT_EQ(f64_at(s, 4 + 88 + 16), 2.0);   // k[2]
  EXPECT_EQ(f64_at(s, 4 + 160), 1.0);       // r[0]
  EXPECT_EQ(f64_at(s, 4 + 160 + 32), 1.0);  // r[4]
  EXPECT_EQ(f64_at(s, 4 + 232 + 16), 2.0);  // p[2] = k[2]
  EXPECT_EQ(f64_at(s, 4 + 232 + 24), 0.0);  // p[3]
  EXPECT_EQ(f64_at(s, 4 + 232 + 48), 4.0);  // p[6] = k[5]
}

TEST(CdrWriterTest, DefaultMarkerLayout) {
  MarkerArray a;
  a.markers.resize(1);
  const std::string s = serialize(a);
  // body: 0 count, then the marker from 4: stamp 4..11, frame_id 12..16, ns 20..24,
  // id/type/action 28..39, pose 40..95 (w at 88), scale 96..119, color 120..135, lifetime 136..143,
  // frame_locked 144, points 148, colors 152, texture_resource 156..160, texture: stamp 164,
  // frame_id 172..176, format 180..184, data 188, uv_coordinates 192, text 196..200, mesh_resource
  // 204..208, mesh_file 212..216 + 220, embedded 224.
  ASSERT_EQ(s.size(), 4u + 225u);
  EXPECT_EQ(u32_at(s, 4 + 0), 1u);
  EXPECT_EQ(u32_at(s, 4 + 32), static_cast<std::uint32_t>(Marker::kCube));
  EXPECT_EQ(f64_at(s, 4 + 88), 1.0);
  EXPECT_EQ(u32_at(s, 4 + 156), 1u);  // texture_resource: "" is length 1 (the NUL)
  EXPECT_EQ(u32_at(s, 4 + 188), 0u);  // texture.data count
  EXPECT_EQ(u32_at(s, 4 + 212), 1u);  // mesh_file.filename
  EXPECT_EQ(u32_at(s, 4 + 220), 0u);  // mesh_file.data count
}

TEST(CdrWriterTest, CompressedImagePrefixPlusDataIsTheMessage) {
  const CompressedImage img =
      jpeg_image(header(5, 6, "CAM_FRONT"), std::string("\xFF\xD8\xFF\xD9", 4));
  EXPECT_EQ(compressed_image_prefix(img.header, img.format, img.data.size()) + img.data,
            serialize(img));
}

TEST(CdrRoundTripTest, EveryMessage) {
  const CompressedImage img =
      jpeg_image(header(5, 6, "CAM_FRONT"), std::string("\xFF\xD8\x00\xFF\xD9", 5));
  auto img2 = deserialize<CompressedImage>(serialize(img));
  ASSERT_TRUE(img2.is_ok()) << img2.status().to_string();
  EXPECT_EQ(img2->header.frame_id, "CAM_FRONT");
  EXPECT_EQ(img2->header.stamp.nanosec, 6u);
  EXPECT_EQ(img2->data, img.data);

  Image raw;
  raw.header = header(1, 2, "cam");
  raw.height = 2;
  raw.width = 3;
  raw.encoding = "bgr8";
  raw.step = 9;
  raw.data = std::string(18, '\x7f');
  auto raw2 = deserialize<Image>(serialize(raw));
  ASSERT_TRUE(raw2.is_ok());
  EXPECT_EQ(raw2->step, 9u);
  EXPECT_EQ(raw2->encoding, "bgr8");
  EXPECT_EQ(raw2->data, raw.data);

  CameraInfo info = camera_info_from_k({{3, 4}, "CAM_BACK"}, 1600, 900,
                                       {1266.4, 0, 816.3, 0, 1266.4, 491.5, 0, 0, 1});
  info.roi = {1, 2, 3, 4, true};
  auto info2 = deserialize<CameraInfo>(serialize(info));
  ASSERT_TRUE(info2.is_ok());
  EXPECT_EQ(info2->k, info.k);
  EXPECT_EQ(info2->p, info.p);
  EXPECT_EQ(info2->d, std::vector<double>(5, 0.0));
  EXPECT_TRUE(info2->roi.do_rectify);
  EXPECT_EQ(info2->roi.width, 4u);

  TFMessage tf;
  tf.transforms.push_back(
      transform(header(1, 0, "map"), "base_link", {1, 2, 3}, {0.1, 0.2, 0.3, 0.9}));
  tf.transforms.push_back(
      transform(header(1, 0, "base_link"), "CAM_FRONT", {4, 5, 6}, {0, 0, 0, 1}));
  auto tf2 = deserialize<TFMessage>(serialize(tf));
  ASSERT_TRUE(tf2.is_ok());
  ASSERT_EQ(tf2->transforms.size(), 2u);
  EXPECT_EQ(tf2->transforms[1].child_frame_id, "CAM_FRONT");
  EXPECT_EQ(tf2->transforms[0].transform.rotation.w, 0.9);

  DiagnosticArray diag;
  diag.header = {{7, 8}, "CAM_FRONT"};
  diag.status.push_back({DiagnosticStatus::kWarn,
                         "faultline/fog",
                         "fog severity 3",
                         "CAM_FRONT",
                         {{"action", "corrupt"}, {"severity", "3"}}});
  auto diag2 = deserialize<DiagnosticArray>(serialize(diag));
  ASSERT_TRUE(diag2.is_ok());
  ASSERT_EQ(diag2->status.size(), 1u);
  EXPECT_EQ(diag2->status[0].level, DiagnosticStatus::kWarn);
  ASSERT_EQ(diag2->status[0].values.size(), 2u);
  EXPECT_EQ(diag2->status[0].values[1].value, "3");

  MarkerArray markers;
  Marker m;
  m.header = {{9, 10}, "map"};
  m.ns = "vehicle.car";
  m.id = 42;
  m.pose = {{1, 2, 3}, {0, 0, 0.5, 0.8}};
  m.scale = {4.5, 1.9, 1.6};
  m.color = {0.0f, 0.8f, 0.2f, 0.5f};
  m.frame_locked = true;
  m.points = {{1, 1, 1}};
  m.colors = {{1, 0, 0, 1}};
  m.text = "car";
  m.texture_resource = "embedded://t";
  m.texture.format = "png";
  m.texture.data = "PNG";
  m.uv_coordinates.resize(2);
  m.uv_coordinates[1].u = 0.25;
  m.mesh_file.filename = "box.stl";
  m.mesh_file.data = "solid";
  m.mesh_use_embedded_materials = true;
  markers.markers = {Marker{}, m};
  markers.markers[0].action = Marker::kDeleteAll;
  auto markers2 = deserialize<MarkerArray>(serialize(markers));
  ASSERT_TRUE(markers2.is_ok()) << markers2.status().to_string();
  ASSERT_EQ(markers2->markers.size(), 2u);
  EXPECT_EQ(markers2->markers[0].action, Marker::kDeleteAll);
  EXPECT_EQ(markers2->markers[1].ns, "vehicle.car");
  EXPECT_EQ(markers2->markers[1].id, 42);
  EXPECT_EQ(markers2->markers[1].scale.x, 4.5);
  EXPECT_EQ(markers2->markers[1].color.g, 0.8f);
  EXPECT_EQ(markers2->markers[1].text, "car");
  EXPECT_EQ(markers2->markers[1].texture_resource, "embedded://t");
  EXPECT_EQ(markers2->markers[1].texture.data, "PNG");
  ASSERT_EQ(markers2->markers[1].uv_coordinates.size(), 2u);
  EXPECT_EQ(markers2->markers[1].uv_coordinates[1].u, 0.25);
  EXPECT_EQ(markers2->markers[1].mesh_file.filename, "box.stl");
  EXPECT_EQ(markers2->markers[1].mesh_file.data, "solid");
  EXPECT_TRUE(markers2->markers[1].mesh_use_embedded_materials);
  EXPECT_TRUE(markers2->markers[1].frame_locked);
}

TEST(CdrReaderTest, EveryTruncationIsAnErrorNotACrash) {
  DiagnosticArray diag;
  diag.header = {{7, 8}, "CAM_FRONT"};
  diag.status.push_back({DiagnosticStatus::kOk, "a", "b", "c", {{"k", "v"}}});
  const std::string full = serialize(diag);
  for (std::size_t n = 0; n < full.size(); ++n) {
    auto r = deserialize<DiagnosticArray>(full.substr(0, n));
    ASSERT_FALSE(r.is_ok()) << "prefix of " << n << " bytes decoded";
    EXPECT_TRUE(r.status().code() == StatusCode::kTruncated ||
                r.status().code() == StatusCode::kCorruptData)
        << r.status().to_string();
  }
  const std::string info =
      serialize(camera_info_from_k({{0, 0}, "cam"}, 2, 2, {1, 0, 0, 0, 1, 0, 0, 0, 1}));
  for (std::size_t n = 0; n < info.size(); ++n) {
    EXPECT_FALSE(deserialize<CameraInfo>(info.substr(0, n)).is_ok()) << n;
  }
}

template <typename M>
void DecodeRandomBytes(std::mt19937& rng) {
  std::uniform_int_distribution<int> byte(0, 255), size(0, 96);
  for (int i = 0; i < 500; ++i) {
    std::string s(kCdrLeHeader);
    const int n = size(rng);
    for (int k = 0; k < n; ++k) s.push_back(static_cast<char>(byte(rng)));
    auto r = deserialize<M>(s);  // ok or an error; never a crash or a huge allocation
    if (!r.is_ok()) {
      EXPECT_FALSE(r.status().message().empty());
    }
  }
}

TEST(CdrReaderTest, RandomBodiesDecodeOrFailCleanly) {
  std::mt19937 rng(18);  // fixed seed: the same bytes every run
  DecodeRandomBytes<CompressedImage>(rng);
  DecodeRandomBytes<Image>(rng);
  DecodeRandomBytes<CameraInfo>(rng);
  DecodeRandomBytes<TFMessage>(rng);
  DecodeRandomBytes<DiagnosticArray>(rng);
  DecodeRandomBytes<MarkerArray>(rng);
}

TEST(CdrReaderTest, EveryFlippedByteOfAMarkerArrayDecodesOrFailsCleanly) {
  MarkerArray a;
  a.markers.resize(2);
  a.markers[1].ns = "vehicle.car";
  a.markers[1].points.resize(2);
  const std::string good = serialize(a);
  for (std::size_t i = 0; i < good.size(); ++i) {
    std::string bad = good;
    bad[i] = static_cast<char>(bad[i] ^ 0xA5);
    auto r = deserialize<MarkerArray>(bad);
    if (r.is_ok()) {
      EXPECT_LE(r->markers.size(), 2u) << i;
    }
  }
}

TEST(CdrReaderTest, LyingDataCountNamesTheField) {
  std::string s = serialize(jpeg_image(header(0, 0, "cam"), "xyz"));
  // body: stamp 0..7, "cam" 8..15, "jpeg" 16..24, pad 25..27, data count at 28.
  ASSERT_EQ(u32_at(s, 4 + 28), 3u);
  const std::uint32_t huge = 0xFFFFFFFFu;
  std::memcpy(&s[4 + 28], &huge, 4);
  auto r = deserialize<CompressedImage>(s);
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(r.status().message().find("sensor_msgs/msg/CompressedImage: field data at byte 32"),
            std::string::npos)
      << r.status().message();
}

TEST(CdrReaderTest, LyingSequenceCountOfStructsIsRejectedBeforeDecoding) {
  std::string s = serialize(TFMessage{});
  const std::uint32_t many = 100000000u;
  std::memcpy(&s[4], &many, 4);
  s += std::string(64, '\0');
  auto r = deserialize<TFMessage>(s);
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("field transforms"), std::string::npos)
      << r.status().message();
}

TEST(CdrReaderTest, StringWithoutNulIsCorrupt) {
  std::string s = serialize(Header{{0, 0}, "ab"});
  s.back() = 'c';
  auto r = deserialize<Header>(s);
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(r.status().message().find("header.frame_id"), std::string::npos);
}

TEST(CdrReaderTest, BigEndianAndShortHeadersAreRefused) {
  std::string s = serialize(Header{{0, 0}, "ab"});
  s[1] = 0x00;  // CDR_BE
  auto be = deserialize<Header>(s);
  ASSERT_FALSE(be.is_ok());
  EXPECT_EQ(be.status().code(), StatusCode::kUnsupported);
  auto shorty = deserialize<Header>(std::string("\x00\x01", 2));
  ASSERT_FALSE(shorty.is_ok());
  EXPECT_EQ(shorty.status().code(), StatusCode::kTruncated);
}

TEST(TimeTest, NuScenesMicrosecondsToTime) {
  const Time t = time_from_us(1532402927647951);
  EXPECT_EQ(t.sec, 1532402927);
  EXPECT_EQ(t.nanosec, 647951000u);
  EXPECT_EQ(to_ns(t), 1532402927647951000);
  const Time neg = time_from_us(-1);
  EXPECT_EQ(neg.sec, -1);
  EXPECT_EQ(neg.nanosec, 999999000u);
  const Time ns = time_from_ns(1'500'000'001);
  EXPECT_EQ(ns.sec, 1);
  EXPECT_EQ(ns.nanosec, 500000001u);
}

TEST(CameraInfoTest, RectifiedFromK) {
  const std::array<double, 9> k{1266.4, 0, 816.3, 0, 1266.4, 491.5, 0, 0, 1};
  const CameraInfo info = camera_info_from_k({{1, 2}, "CAM_FRONT"}, 1600, 900, k);
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  EXPECT_EQ(info.d, std::vector<double>(5, 0.0));
  EXPECT_EQ(info.r, (std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_EQ(info.p, (std::array<double, 12>{1266.4, 0, 816.3, 0, 0, 1266.4, 491.5, 0, 0, 0, 1, 0}));
  EXPECT_EQ(info.width, 1600u);
  EXPECT_EQ(info.height, 900u);
  EXPECT_EQ(info.header.frame_id, "CAM_FRONT");
}

}  // namespace
}  // namespace faultline::ros2
