// Writes the bags that tests/mcap_js/validate_mcap.mjs checks independently (CTest fixture):
// fixture_{zstd,lz4,none}.mcap with Foxglove and Faultline schemas, and fixture_corrupt.mcap
// (one flipped byte inside a chunk, which the validator must reject).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include "bag/foxglove.hpp"
#include "bag/reader.hpp"
#include "bag/writer.hpp"
#include "foxglove/ImageAnnotations.pb.h"

namespace {

using namespace faultline;
constexpr int kSteps = 10;
constexpr int kMessagesPerStep =
    23;  // 6 x (image, info, tf) + ego tf + 2 markers + raw image + frame
const char* const kCameras[] = {"CAM_FRONT", "CAM_FRONT_LEFT", "CAM_FRONT_RIGHT",
                                "CAM_BACK",  "CAM_BACK_LEFT",  "CAM_BACK_RIGHT"};

msgs::CameraFrame make_frame(const char* camera, int step) {
  msgs::CameraFrame f;
  f.mutable_header()->set_seq(static_cast<std::uint64_t>(step + 1));
  f.mutable_header()->set_capture_stamp_ns(1'533'151'603'512'404'000 + step * 83'333'333LL);
  f.set_camera(camera);
  f.set_encoding("jpeg");
  f.set_width(1600);
  f.set_height(900);
  for (double k : {1266.4, 0.0, 816.3, 0.0, 1266.4, 491.5, 0.0, 0.0, 1.0}) f.add_intrinsics(k);
  f.mutable_sensor_to_ego()->mutable_translation()->set_x(1.7);
  f.mutable_sensor_to_ego()->mutable_rotation()->set_w(0.5);
  f.mutable_sensor_to_ego()->mutable_rotation()->set_x(-0.5);
  f.mutable_sensor_to_ego()->mutable_rotation()->set_y(0.5);
  f.mutable_sensor_to_ego()->mutable_rotation()->set_z(-0.5);
  f.mutable_ego_pose()->mutable_translation()->set_x(600.0 + step);
  f.mutable_ego_pose()->mutable_rotation()->set_w(1.0);
  return f;
}

int write_bag(const std::string& path, bag::Compression compression) {
  bag::WriterOptions opts;
  opts.compression = compression;
  opts.chunk_size_bytes = 64 * 1024;
  auto opened = bag::Writer::open(path, opts);
  if (!opened) {
    std::fprintf(stderr, "%s\n", opened.status().to_string().c_str());
    return 1;
  }
  bag::Writer& w = **opened;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  std::map<std::string, std::uint16_t> ch;
  for (const char* cam : kCameras) {
    ch[bag::image_topic(cam)] = *w.channel_for<foxglove::CompressedImage>(bag::image_topic(cam));
    ch[bag::camera_info_topic(cam)] =
        *w.channel_for<foxglove::CameraCalibration>(bag::camera_info_topic(cam));
  }
  ch["/tf"] = *w.channel_for<foxglove::FrameTransform>(bag::kTfTopic);
  ch["gt"] = *w.channel_for<foxglove::SceneUpdate>(bag::kAnnotationsTopic);
  ch["det"] = *w.channel_for<foxglove::SceneUpdate>(bag::kDetectionsTopic);
  ch["raw"] =
      *w.channel_for<foxglove::RawImage>("/cam_front/image_raw", {{"frame_id", "cam_front"}});
  ch["frame"] = *w.channel_for<msgs::CameraFrame>("/faultline/frames");
  if (!w.write_metadata("faultline.run", {{"seed", "7"}, {"schema_version", "1"}})) return 1;

  std::uint64_t written = 0;
  auto put = [&](std::uint16_t channel, std::uint64_t seq, StampNs t,
                 const google::protobuf::Message& m) {
    if (w.write_proto(channel, seq, t, t, m)) ++written;
  };
  for (int step = 0; step < kSteps; ++step) {
    const auto seq = static_cast<std::uint64_t>(step + 1);
    for (const char* cam : kCameras) {
      const msgs::CameraFrame f = make_frame(cam, step);
      const StampNs t = f.header().capture_stamp_ns();
      std::string jpeg(20'000, '\0');
      for (char& c : jpeg) c = static_cast<char>(byte(rng));
      put(ch[bag::image_topic(cam)], seq, t, bag::to_compressed_image(f, jpeg));
      put(ch[bag::camera_info_topic(cam)], seq, t, bag::to_camera_calibration(f));
      put(ch["/tf"], seq, t, bag::sensor_transform(f));
    }
    const msgs::CameraFrame front = make_frame("CAM_FRONT", step);
    const StampNs t = front.header().capture_stamp_ns();
    put(ch["/tf"], seq, t, bag::ego_transform(front));
    bag::GtBox box{
        "e3f1a9b0c", "vehicle.car", {610.0 + step, 1.0, 0.5}, {1.9, 4.5, 1.6}, {0.92, 0, 0, 0.38}};
    put(ch["gt"], seq, t, bag::gt_scene_update({box}, t));
    msgs::DetectionArray dets;
    auto* d = dets.add_detections();
    for (double v : {611.0, 1.2, 0.5}) d->add_translation(v);
    for (double v : {1.8, 4.4, 1.5}) d->add_size(v);
    for (double v : {0.92, 0.0, 0.0, 0.38}) d->add_rotation(v);
    d->set_detection_name("car");
    d->set_detection_score(0.8);
    put(ch["det"], seq, t, bag::detection_scene_update(dets, t));
    msgs::CameraFrame raw_frame = front;
    raw_frame.set_encoding("bgr8");
    raw_frame.set_width(64);
    raw_frame.set_height(48);
    raw_frame.set_step(64 * 3);
    std::string pixels(64 * 48 * 3, '\0');
    for (std::size_t i = 0; i < pixels.size(); ++i)
      pixels[i] = static_cast<char>((i / 3 + static_cast<std::size_t>(step)) % 256);
    put(ch["raw"], seq, t, bag::to_raw_image(raw_frame, pixels));
    put(ch["frame"], seq, t, front);
  }
  if (Status s = w.close(); !s) {
    std::fprintf(stderr, "%s: %s\n", path.c_str(), s.to_string().c_str());
    return 1;
  }
  if (written != static_cast<std::uint64_t>(kSteps * kMessagesPerStep)) {
    std::fprintf(stderr, "%s: wrote %llu messages, expected %d\n", path.c_str(),
                 static_cast<unsigned long long>(written), kSteps * kMessagesPerStep);
    return 1;
  }
  std::printf("%s: %llu messages\n", path.c_str(), static_cast<unsigned long long>(written));
  return 0;
}

// Copies `in` to `out` with one byte flipped in the middle of the second chunk's records.
int write_corrupt(const std::string& in, const std::string& out) {
  auto reader = bag::Reader::open(in);
  if (!reader || !(*reader)->load_summary()) return 1;
  const auto& chunks = (*reader)->summary().chunk_indexes;
  if (chunks.size() < 2) return 1;
  std::ifstream src(in, std::ios::binary);
  std::string bytes{std::istreambuf_iterator<char>(src), std::istreambuf_iterator<char>()};
  bytes[static_cast<std::size_t>(chunks[1].chunk_start_offset + chunks[1].chunk_length / 2)] ^=
      0x01;
  std::ofstream dst(out, std::ios::binary);
  dst.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  std::printf("%s: flipped one byte in the chunk at offset %llu\n", out.c_str(),
              static_cast<unsigned long long>(chunks[1].chunk_start_offset));
  return dst.good() ? 0 : 1;
}

// Tiny seed bags for the fuzzer corpus (tests/bag/corpus/): each compression, a few chunks.
int write_seeds(const std::string& dir) {
  int rc = 0;
  for (const auto c : {bag::Compression::kNone, bag::Compression::kZstd, bag::Compression::kLz4}) {
    const std::string path = dir + "/seed_" + bag::display_name(c) + ".mcap";
    bag::WriterOptions opts;
    opts.compression = c;
    opts.chunk_size_bytes = 256;
    auto w = bag::Writer::open(path, opts);
    if (!w) return 1;
    const auto a =
        *(*w)->add_channel("/a", (*w)->add_schema("t.A", "protobuf", "xy"), {{"k", "v"}});
    const auto b = *(*w)->add_channel("/b", 0, {}, "raw");
    for (int i = 0; i < 6; ++i) {
      const std::string payload(static_cast<std::size_t>(40 + 30 * i), static_cast<char>('a' + i));
      rc |= (*w)->write(i % 2 ? a : b, static_cast<std::uint64_t>(i), 100 - 10 * i, 5, payload) ? 0
                                                                                                : 1;
    }
    rc |= (*w)->write_metadata("m", {{"x", "1"}}) ? 0 : 1;
    rc |= (*w)->close() ? 0 : 1;
  }
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--seeds") return write_seeds(argv[2]);
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR | --seeds CORPUS_DIR\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  int rc = 0;
  rc |= write_bag(dir + "/fixture_zstd.mcap", bag::Compression::kZstd);
  rc |= write_bag(dir + "/fixture_lz4.mcap", bag::Compression::kLz4);
  rc |= write_bag(dir + "/fixture_none.mcap", bag::Compression::kNone);
  rc |= write_corrupt(dir + "/fixture_none.mcap", dir + "/fixture_corrupt.mcap");
  return rc;
}
