// `bag corrupt` on a Faultline recording: the injector's seeds, fault state and events.
#include "bag_corrupt_fixture.hpp"
#include "runtime/bag_corrupt.hpp"

namespace faultline::runtime {
namespace {

using namespace bag_corrupt_fixture;  // NOLINT(google-build-using-namespace): the shared fixture

TEST_F(BagCorruptTest, FaultlineRecordingGetsTheInjectorsSeedsStateAndEvents) {
  // A recording as `bag record` / `bag convert` write it: a camera-frame replay channel, the
  // Foxglove view of the same topic, a two-part proto channel and the run's Metadata record.
  const std::string path = (dir_ / "run.mcap").string();
  const std::string topic = "/cam_front/image_rect_compressed";
  std::vector<std::string> jpegs;
  {
    auto w = bag::Writer::open(path, {});
    ASSERT_TRUE(w);
    ASSERT_TRUE((*w)->write_metadata("faultline.run", {{"tool", "test"}}));
    const auto d = msgs::CameraFrame::descriptor();
    const auto schema =
        (*w)->add_schema(d->full_name(), "protobuf", bag::build_file_descriptor_set(d));
    const auto raw = *(*w)->add_channel(
        std::string(kRawTopicPrefix) + topic, schema,
        {{kMetaTopic, topic}, {kMetaFrames, "3"}, {kMetaType, d->full_name()}}, kMultipartEncoding);
    const auto view = *(*w)->channel_for<foxglove::CompressedImage>(topic);
    const auto sync = *(*w)->channel_for<msgs::SampleBoundary>(
        "/sync/sample", {{kMetaTopic, "/sync/sample"}, {kMetaFrames, "2"}});
    for (int i = 0; i < 6; ++i) {
      const StampNs t = kT0 + i * kPeriod;
      jpegs.push_back(jpeg_of(picture(48, 32, i)));
      msgs::CameraFrame h;
      h.mutable_header()->set_seq(static_cast<std::uint64_t>(i + 1));
      h.mutable_header()->set_capture_stamp_ns(t);
      h.mutable_header()->set_frame_id("CAM_FRONT");
      h.mutable_header()->set_publisher("nusc_player");
      h.set_camera("CAM_FRONT");
      h.set_encoding("jpeg");
      h.set_width(48);
      h.set_height(32);
      h.set_source_seq(static_cast<std::uint64_t>(100 + i));
      h.set_is_key_frame(i % 2 == 0);
      h.set_payload_bytes(static_cast<std::uint32_t>(jpegs.back().size()));
      ASSERT_TRUE(
          (*w)->write(raw, i + 1, t, t, encode_multipart(h.SerializeAsString(), jpegs.back())));
      foxglove::CompressedImage v;
      v.set_frame_id("CAM_FRONT");
      v.set_format("jpeg");
      v.set_data(jpegs.back());
      ASSERT_TRUE((*w)->write_proto(view, i + 1, t, t, v));
      msgs::SampleBoundary b;
      b.set_sample_token("s" + std::to_string(i));
      ASSERT_TRUE((*w)->write_proto(sync, i + 1, t + 1, t + 1, b));
    }
    ASSERT_TRUE((*w)->close());
  }
  // A Faultline frame's stamp is not rewritten here: timestamp_skew on its topic is refused by
  // name.
  auto skew = config(path, "skewed.mcap");
  skew.faults.push_back(parse_topic_fault(topic + "=timestamp_skew:2", corruption::RngMode::Fast));
  auto refused = corrupt_bag(skew, stop_);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.status().message().find("timestamp_skew only to ROS 2 image topics"),
            std::string::npos)
      << refused.status().message();
  EXPECT_FALSE(fs::exists(skew.output));

  auto cfg = config(path, "out.mcap");
  const std::string schedule = (dir_ / "faults.yaml").string();
  std::ofstream(schedule) << topic << ":\n  - {type: fog, level: mid, frames: key}\n";
  cfg.faults = load_fault_schedule(schedule, corruption::RngMode::Fast);
  auto counts = corrupt_bag(cfg, stop_);
  ASSERT_TRUE(counts) << counts.status().to_string();
  EXPECT_EQ(counts->frames, 6u);
  EXPECT_EQ(counts->corrupted, 3u);  // key frames only
  EXPECT_EQ(counts->unchanged, 3u);

  const Bag a = read_bag(path), b = read_bag(cfg.output);
  for (const char* same :
       {"/sync/sample", "/cam_front/image_rect_compressed"}) {  // the view stays clean
    std::vector<Message> x, y;
    for (const auto* m : a.on(same)) x.push_back(*m);
    for (const auto* m : b.on(same)) y.push_back(*m);
    EXPECT_TRUE(x == y) << same;
    EXPECT_EQ(b.channels.at(same).metadata, a.channels.at(same).metadata);
  }
  auto reader = bag::Reader::open(cfg.output);
  auto metadata = (*reader)->read_metadata();
  ASSERT_TRUE(metadata);
  ASSERT_EQ(metadata->size(), 1u);
  EXPECT_EQ((*metadata)[0].name, "faultline.run");

  const auto src = a.on(std::string(kRawTopicPrefix) + topic),
             dst = b.on(std::string(kRawTopicPrefix) + topic);
  ASSERT_EQ(dst.size(), 6u);
  for (std::size_t i = 0; i < 6; ++i) {
    if (i % 2 == 1) {
      EXPECT_EQ(dst[i]->data, src[i]->data) << i;
      continue;
    }
    auto parts = decode_multipart(dst[i]->data);
    ASSERT_TRUE(parts);
    msgs::CameraFrame h;
    ASSERT_TRUE(h.ParseFromArray(parts->header.data(), static_cast<int>(parts->header.size())));
    EXPECT_EQ(h.source_seq(), 100 + i);
    EXPECT_EQ(h.payload_bytes(), parts->payload.size());
    ASSERT_EQ(h.fault().faults_size(), 1);
    EXPECT_EQ(h.fault().action(), msgs::FAULT_ACTION_CORRUPT);
    const auto seed =
        policy::frame_seed(7, 0, 100 + i);  // what the live injector draws for this frame
    EXPECT_EQ(h.fault().faults(0).seed(), seed);
    auto input =
        codec::decode_jpeg(reinterpret_cast<const std::uint8_t*>(jpegs[i].data()), jpegs[i].size());
    rng::FastRng r(seed);
    auto expected = corruption::corrupt(
        *input, corruption::Corruption::Fog,
        corruption::severity_for(corruption::Corruption::Fog, corruption::Level::Mid), r);
    auto jpeg = codec::encode_jpeg(*expected, 95);
    EXPECT_EQ(parts->payload, std::string(jpeg->begin(), jpeg->end())) << i;
  }
  const auto events = b.on("/faultline/faults");
  ASSERT_EQ(events.size(), 6u);
  EXPECT_EQ(b.schemas.at("/faultline/faults").name, "faultline.msgs.FaultEvent");
  EXPECT_EQ(b.channels.at("/faultline/faults").metadata.at(kMetaTopic), "/faultline/faults");
  for (std::size_t i = 0; i < events.size(); ++i) {
    msgs::FaultEvent e;
    ASSERT_TRUE(e.ParseFromString(events[i]->data));
    EXPECT_EQ(e.camera(), "CAM_FRONT");
    EXPECT_EQ(e.source_seq(), 100 + i);
    EXPECT_EQ(e.state().action(),
              i % 2 == 0 ? msgs::FAULT_ACTION_CORRUPT : msgs::FAULT_ACTION_PASS);
  }
}

}  // namespace
}  // namespace faultline::runtime
