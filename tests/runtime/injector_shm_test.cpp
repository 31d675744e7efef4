// The injector with output_shm: camera frames leave through its shared-memory ring, read by a C++
// subscriber with transport::ShmCameraReader byte for byte as sent, every seq present; a frame
// larger than a slot is refused and counted; the ring file exists while the injector lives and is
// removed with it.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <future>

#include "common/logging.hpp"
#include "runtime/engine_policy.hpp"
#include "runtime/injector_loop.hpp"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime {
namespace {

bool file_exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

TEST(InjectorShmTest, FramesGoThroughTheRingByteIdenticalAndOversizeIsRefused) {
  const std::string dir = ::testing::TempDir() + "shm_out_" + std::to_string(::getpid());
  transport::PublisherConfig pc;
  pc.endpoint = "ipc://" + dir + "_camera.sock";
  pc.snd_hwm = 1000;
  transport::Publisher camera(pc);
  constexpr int kWidth = 16, kHeight = 8, kFrames = 12;
  InjectorConfig ic;
  ic.input_endpoints = {camera.endpoint()};
  ic.output_endpoint = "ipc://" + dir + "_injector.sock";
  ic.input_hwm = ic.output_hwm = 1000;
  ic.decode = true;
  ic.wait_subscribers = 1;
  ic.workers = 2;
  ic.output_shm = true;
  ic.output_shm_dir = ::testing::TempDir();
  ic.shm_slots = 64;  // more than the frames: none can be overwritten, whatever the timing
  ic.shm_slot_bytes = kWidth * kHeight * 3;
  std::string ring_path;
  {
    InjectorLoop injector(ic, "fault_injector",
                          make_frame_policy(YAML::Node(), "", 3, "fault_injector"),
                          logging::make_node_logger("shm_test", "error"));
    ring_path = injector.output_shm_path();
    ASSERT_EQ(ring_path.rfind(::testing::TempDir() + "/faultline-fault_injector-", 0), 0u)
        << ring_path;
    EXPECT_TRUE(file_exists(ring_path));
    transport::SubscriberConfig sc;
    sc.endpoints = {injector.output_endpoint()};
    sc.topics = {"/faulty/", "/sync/sample"};
    sc.rcv_hwm = 1000;
    transport::RawSubscriber out(sc);
    std::atomic<bool> stop{false};
    auto rc = std::async(std::launch::async, [&] { return injector.run(stop); });
    ASSERT_TRUE(camera.wait_for_subscribers("/cam_front", 1, 20 * kNsPerSec).is_ok());
    std::vector<std::vector<std::uint8_t>> sent;
    for (int i = 0; i <= kFrames; ++i) {
      const bool big = i == kFrames / 2;  // one frame twice the slot: refused by the ring
      const int height = big ? 2 * kHeight : kHeight;
      std::vector<std::uint8_t> pixels(static_cast<std::size_t>(kWidth * height * 3));
      for (std::size_t k = 0; k < pixels.size(); ++k)
        pixels[k] = static_cast<std::uint8_t>(k * 3 + i * 11);
      if (!big) sent.push_back(pixels);
      msgs::CameraFrame h;
      h.mutable_header()->set_seq(static_cast<std::uint64_t>(i + 1));
      h.mutable_header()->set_publisher("camera");
      h.set_camera("CAM_FRONT");
      h.set_encoding("bgr8");
      h.set_width(kWidth);
      h.set_height(static_cast<std::uint32_t>(height));
      h.set_step(kWidth * 3);
      h.set_source_seq(static_cast<std::uint64_t>(i + 1));
      ASSERT_TRUE(
          transport::send_camera_frame(
              camera, "/cam_front/image_raw", h,
              transport::Payload::of(std::make_shared<const std::vector<std::uint8_t>>(pixels)))
              .is_ok());
    }
    msgs::SampleBoundary last;
    last.mutable_header()->set_seq(1);
    last.set_sample_token("s");
    last.set_last_in_run(true);
    ASSERT_TRUE(transport::send_message(camera, "/sync/sample", last).is_ok());

    transport::ShmCameraReader reader;
    std::vector<std::vector<std::uint8_t>> received;
    std::vector<std::uint64_t> seqs;
    bool saw_last = false;
    const StampNs deadline = monotonic_now_ns() + 60 * kNsPerSec;  // watchdog, not synchronisation
    while (!saw_last && monotonic_now_ns() < deadline) {
      auto r = out.receive(50 * kNsPerMs);
      if (!r.is_ok()) continue;
      if (r->topic() == "/sync/sample") {
        saw_last = true;
        continue;
      }
      ASSERT_FALSE(r->has_payload());  // only the descriptor on the socket
      auto view = reader.read(*r);
      ASSERT_TRUE(view.is_ok()) << view.status().message();
      received.emplace_back(view->payload, view->payload + view->payload_size);
      EXPECT_TRUE(reader.intact(*view));
      EXPECT_EQ(view->header.shm().path(), ring_path);
      seqs.push_back(view->header.header().seq());
    }
    EXPECT_TRUE(saw_last);
    stop = true;
    EXPECT_EQ(rc.get(), 0);
    EXPECT_EQ(received, sent);
    std::vector<std::uint64_t> expected;
    for (int k = 0; k <= kFrames; ++k) {
      if (k != kFrames / 2) expected.push_back(static_cast<std::uint64_t>(k + 1));
    }
    EXPECT_EQ(seqs, expected);  // the refused frame's seq is a gap: subscribers count it as lost
    EXPECT_EQ(reader.overwritten(), 0u);
    EXPECT_EQ(injector.counts().oversize_refused, 1u);
    EXPECT_EQ(injector.counts().frames_out, static_cast<std::uint64_t>(kFrames));
  }
  EXPECT_FALSE(file_exists(ring_path));  // removed with the injector
}

}  // namespace
}  // namespace faultline::runtime
