// The ROS 2 launch files end to end, through `faultline launch` and real node processes, seen from
// a DDS peer in this test (Cyclone DDS, loopback, domain 100 + pid % 100). launch/ros2_replay.yaml
// on a small generated nuScenes dataset: every camera frame the player sent arrives with its
// nuScenes stamp and frame_id, its CameraInfo, one DiagnosticArray, the ego pose on /tf and the six
// cameras on /tf_static. launch/ros2_proxy.yaml: two ROS 2 camera topics come back faulted as
// <topic>/faulty with their stamps and frame_ids.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "codec/jpeg.hpp"
#include "dataset/synth.hpp"
#include "diagnostic_msgs.h"
#include "ros2/naming.hpp"
#include "ros2dds/convert.hpp"
#include "ros2dds/dds.hpp"
#include "runtime/frame_source.hpp"
#include "sensor_msgs.h"
#include "tf2_msgs.h"

extern char** environ;

namespace faultline::ros2dds {
namespace {

// A 32x24 JPEG.
std::vector<std::uint8_t> JpegForTest() {
  return codec::encode_jpeg(cv::Mat(24, 32, CV_8UC3, cv::Scalar(40, 120, 200)), 90).value();
}

// The replay's ROS 2 names are nuScenes' (names: nuscenes): /CAM_FRONT/image_rect_compressed,
// frame_id CAM_FRONT.
const char* kCameras[] = {"CAM_FRONT", "CAM_FRONT_RIGHT", "CAM_FRONT_LEFT",
                          "CAM_BACK",  "CAM_BACK_LEFT",   "CAM_BACK_RIGHT"};

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

pid_t SpawnLogged(std::vector<std::string> args, const std::string& log) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = -1;
  if (posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&fa);
  return pid;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class Ros2LaunchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-ros2-replay-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
    dataset::SynthOptions o;
    o.out_dir = dir_ + "/nuscenes";
    o.scenes = 1;
    o.seconds = 2.0;
    o.image_width = 160;
    o.image_height = 90;
    o.jpeg_quality = 70;
    ASSERT_TRUE(dataset::write_synthetic_dataset(o).is_ok());
    ::setenv("CYCLONEDDS_URI",
             "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
             "address=\"127.0.0.1\"/>"
             "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
             "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>19</"
             "MaxAutoParticipantIndex>"
             "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>",
             1);
    ::setenv("FAULTLINE_RUN_DIR", (dir_ + "/graph").c_str(), 1);
  }
  void TearDown() override {
    if (!HasFailure()) std::filesystem::remove_all(dir_);
  }
  std::string dir_;
};

TEST_F(Ros2LaunchTest, EveryFrameReachesRos2WithCalibrationPoseAndFaults) {
  // What the player will send: the dataset's camera frames whose image file exists.
  auto source = runtime::NuScenesFrameSource::open(dir_ + "/nuscenes", "v1.0-mini", {});
  ASSERT_TRUE(source) << source.status().message();
  std::map<std::string, std::vector<std::int64_t>> expected_us;  // channel -> timestamps
  for (const auto& f : (*source)->frames()) {
    if (!std::filesystem::exists(dir_ + "/nuscenes/" + f.filename)) continue;
    expected_us[f.channel].push_back(f.timestamp_us);
  }
  ASSERT_EQ(expected_us.size(), 6u);

  const int domain = 100 + static_cast<int>(::getpid() % 100);
  Participant p(domain, "");
  const TopicQos all{true, 10000, false};
  std::vector<std::unique_ptr<Reader>> images, infos;
  std::string advertise = "[";
  for (const char* cam : kCameras) {
    images.push_back(std::make_unique<Reader>(p, &sensor_msgs_msg_dds__CompressedImage__desc,
                                              ros2::nuscenes_image_topic(cam), all));
    infos.push_back(std::make_unique<Reader>(p, &sensor_msgs_msg_dds__CameraInfo__desc,
                                             ros2::nuscenes_camera_info_topic(cam), all));
    advertise += std::string(advertise.size() > 1 ? "," : "") + "/faulty/" + Lower(cam) +
                 "/image_rect_compressed";
  }
  advertise += "]";
  Reader faults(p, &diagnostic_msgs_msg_dds__DiagnosticArray__desc, "/faultline/faults", all);
  Reader tf(p, &tf2_msgs_msg_dds__TFMessage__desc, "/tf", all);
  Reader tf_static(p, &tf2_msgs_msg_dds__TFMessage__desc, "/tf_static", TopicQos{true, 1, true});

  const std::string ipc = "ipc://" + dir_ + "/";
  std::vector<std::string> args{std::string(FAULTLINE_BIN_DIR) + "/faultline",
                                "launch",
                                std::string(FAULTLINE_SOURCE_DIR) + "/launch/ros2_replay.yaml",
                                "-p",
                                "nusc_player.dataroot:=" + dir_ + "/nuscenes",
                                "-p",
                                "nusc_player.rate:=0",
                                "-p",
                                "nusc_player.endpoint:=" + ipc + "player",
                                "-p",
                                "nusc_player.hwm:=1000",
                                "-p",
                                "fault_injector.input_endpoints:=[" + ipc + "player]",
                                "-p",
                                "fault_injector.output_endpoint:=" + ipc + "injector",
                                "-p",
                                "fault_injector.input_hwm:=1000",
                                "-p",
                                "fault_injector.output_hwm:=1000",
                                "-p",
                                "fault_injector.corruption:=brightness/mid",
                                "-p",
                                "ros2_out.input_endpoints:=[" + ipc + "injector]",
                                "-p",
                                "ros2_out.input_hwm:=1000",
                                "-p",
                                "ros2_out.domain_id:=" + std::to_string(domain),
                                "-p",
                                "ros2_out.advertise:=" + advertise,
                                "-p",
                                "ros2_out.wait_readers:=1"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string log = dir_ + "/launch.log";
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = -1;
  ASSERT_EQ(posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&fa);

  // Take samples while the run goes (the launch ends when ros2_out's readers acknowledged the last
  // frame).
  std::map<std::string, std::vector<StampNs>> got;            // channel -> stamps, in arrival order
  std::map<std::string, std::vector<std::string>> frame_ids;  // channel -> frame_ids
  std::map<std::string, std::size_t> infos_got;
  std::size_t events = 0, corrupt = 0, poses = 0;
  std::vector<std::string> static_children;
  auto drain = [&] {
    for (std::size_t i = 0; i < 6; ++i) {
      (void)images[i]->take(
          [&](const void* s) {
            const auto* m = static_cast<const sensor_msgs_msg_dds__CompressedImage_*>(s);
            got[kCameras[i]].push_back(
                ns_from_time({m->header.stamp.sec, m->header.stamp.nanosec}));
            frame_ids[kCameras[i]].push_back(m->header.frame_id);
          },
          1000);
      (void)infos[i]->take(
          [&](const void* s) {
            const auto* m = static_cast<const sensor_msgs_msg_dds__CameraInfo_*>(s);
            if (std::string(m->distortion_model) == "plumb_bob" && m->k[8] == 1.0 && m->p[3] == 0.0)
              ++infos_got[kCameras[i]];
          },
          1000);
    }
    (void)faults.take(
        [&](const void* s) {
          const auto* m = static_cast<const diagnostic_msgs_msg_dds__DiagnosticArray_*>(s);
          ++events;
          if (m->status._length == 1 &&
              std::string(m->status._buffer[0].message).rfind("corrupt: brightness/", 0) == 0)
            ++corrupt;
        },
        1000);
    (void)tf.take(
        [&](const void* s) {
          const auto* m = static_cast<const tf2_msgs_msg_dds__TFMessage_*>(s);
          if (m->transforms._length == 1 &&
              std::string(m->transforms._buffer[0].header.frame_id) == "map" &&
              std::string(m->transforms._buffer[0].child_frame_id) == "base_link") {
            ++poses;
          }
        },
        1000);
    (void)tf_static.take(
        [&](const void* s) {
          const auto* m = static_cast<const tf2_msgs_msg_dds__TFMessage_*>(s);
          static_children.clear();
          for (std::uint32_t k = 0; k < m->transforms._length; ++k)
            static_children.push_back(m->transforms._buffer[k].child_frame_id);
        },
        1000);
  };
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(90);
  while (waitpid(pid, &status, WNOHANG) == 0) {
    drain();
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGINT);
      waitpid(pid, &status, 0);
      FAIL() << "launch did not end within 90 s\n" << ReadText(log);
    }
    std::this_thread::sleep_for(
        std::chrono::milliseconds(20));  // polling the readers; not an assertion
  }
  drain();
  ASSERT_TRUE(WIFEXITED(status)) << ReadText(log);
  EXPECT_EQ(WEXITSTATUS(status), 0) << ReadText(log);

  std::size_t total = 0;
  for (const char* cam : kCameras) {
    const auto& want = expected_us[cam];
    std::vector<StampNs> want_ns;
    for (auto us : want) want_ns.push_back(ns_from_time(time_from_us(us)));
    EXPECT_EQ(got[cam], want_ns) << cam << ": every frame, in order, with its nuScenes stamp";
    for (const auto& id : frame_ids[cam])
      ASSERT_EQ(id, cam) << "the same frame_id as bag convert --format ros2";
    EXPECT_EQ(infos_got[cam], want.size()) << cam;
    total += want.size();
  }
  EXPECT_GT(total, 100u) << "2 s x 12 Hz x 6 cameras, less the dataset's missing images";
  EXPECT_EQ(events, total) << "one DiagnosticArray per frame";
  EXPECT_GT(corrupt, 0u);
  EXPECT_EQ(poses, total) << "one /tf per frame (each camera frame has its own timestamp)";
  std::sort(static_children.begin(), static_children.end());
  std::vector<std::string> cams(std::begin(kCameras), std::end(kCameras));
  std::sort(cams.begin(), cams.end());
  EXPECT_EQ(static_children, cams) << "/tf_static carries all six cameras";
}

TEST_F(Ros2LaunchTest, ProxyRepublishesEachTopicFaulted) {
  constexpr int kFrames = 12;
  const int domain = 100 + static_cast<int>(::getpid() % 100);
  Participant p(domain, "");
  const TopicQos all{true, 10000, false};
  Writer front(p, &sensor_msgs_msg_dds__CompressedImage__desc, "/front/image_raw/compressed",
               TopicQos{});
  Writer rear(p, &sensor_msgs_msg_dds__Image__desc, "/rear/image_raw", TopicQos{});
  Reader front_out(p, &sensor_msgs_msg_dds__CompressedImage__desc,
                   "/front/image_raw/compressed/faulty", all);
  Reader rear_out(p, &sensor_msgs_msg_dds__CompressedImage__desc, "/rear/image_raw/faulty", all);
  Reader front_info(p, &sensor_msgs_msg_dds__CameraInfo__desc, "/front/camera_info/faulty", all);
  Reader rear_info(p, &sensor_msgs_msg_dds__CameraInfo__desc, "/rear/camera_info/faulty", all);
  Reader faults(p, &diagnostic_msgs_msg_dds__DiagnosticArray__desc, "/faultline/faults", all);

  const std::string ipc = "ipc://" + dir_ + "/";
  const std::string d = std::to_string(domain);
  const pid_t pid = SpawnLogged(
      {std::string(FAULTLINE_BIN_DIR) + "/faultline",
       "launch",
       std::string(FAULTLINE_SOURCE_DIR) + "/launch/ros2_proxy.yaml",
       "-p",
       "ros2_in.topics:=[/front/image_raw/compressed, /rear/image_raw]",
       "-p",
       "ros2_in.domain_id:=" + d,
       "-p",
       "ros2_in.endpoint:=" + ipc + "in",
       "-p",
       "fault_injector.input_endpoints:=[" + ipc + "in]",
       "-p",
       "fault_injector.output_endpoint:=" + ipc + "out",
       "-p",
       "fault_injector.corruption:=brightness/mid",
       "-p",
       "ros2_out.input_endpoints:=[" + ipc + "out]",
       "-p",
       "ros2_out.domain_id:=" + d,
       "-p",
       "ros2_out.advertise:=[/faulty/ros2/front/image_raw/compressed, /faulty/ros2/rear/image_raw]",
       "-p",
       "ros2_out.wait_readers:=1"},
      dir_ + "/launch.log");
  ASSERT_GT(pid, 0);
  auto stop_launch = [&] {
    kill(pid, SIGINT);
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  };
  // Connected end to end: ros2_in subscribed (after the injector and ros2_out joined), ros2_out's
  // writers matched.
  if (!front.wait_for_readers(1, 30 * kNsPerSec).is_ok() ||
      !rear.wait_for_readers(1, 30 * kNsPerSec).is_ok()) {
    stop_launch();
    FAIL() << "ros2_in did not subscribe\n" << ReadText(dir_ + "/launch.log");
  }
  for (Reader* r : {&front_out, &rear_out, &front_info, &rear_info, &faults}) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (r->status().matched < 1 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));  // discovery; not an assertion
    }
    ASSERT_EQ(r->status().matched, 1u) << r->ros_topic() << "\n" << ReadText(dir_ + "/launch.log");
  }
  const StampNs t0 = 1533151603512404000;
  const std::vector<std::uint8_t> jpeg = JpegForTest();
  for (int i = 0; i < kFrames; ++i) {
    const RosTime t = time_from_ns(t0 + i * 83'333'333);
    sensor_msgs_msg_dds__CompressedImage_ a{};
    a.header.stamp = {t.sec, t.nanosec};
    std::string fid_a = "front_optical";
    a.header.frame_id = fid_a.data();
    std::string fmt = "jpeg";
    a.format = fmt.data();
    a.data._buffer = const_cast<std::uint8_t*>(jpeg.data());
    a.data._length = a.data._maximum = static_cast<std::uint32_t>(jpeg.size());
    ASSERT_TRUE(front.write(&a).is_ok());
    std::vector<std::uint8_t> px(16 * 8 * 3, static_cast<std::uint8_t>(10 * i));
    sensor_msgs_msg_dds__Image_ b{};
    b.header.stamp = {t.sec, t.nanosec};
    std::string fid_b = "rear_optical";
    b.header.frame_id = fid_b.data();
    std::string enc = "rgb8";
    b.encoding = enc.data();
    b.width = 16;
    b.height = 8;
    b.step = 48;
    b.data._buffer = px.data();
    b.data._length = b.data._maximum = static_cast<std::uint32_t>(px.size());
    ASSERT_TRUE(rear.write(&b).is_ok());
    ASSERT_TRUE(front.wait_for_acks(10 * kNsPerSec).is_ok());
    ASSERT_TRUE(rear.wait_for_acks(10 * kNsPerSec).is_ok());
  }
  std::vector<StampNs> got_front, got_rear;
  std::vector<std::string> ids_front, ids_rear;
  std::size_t infos = 0, events = 0, corrupt = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while ((got_front.size() < kFrames || got_rear.size() < kFrames || events < 2 * kFrames ||
          infos < 2 * kFrames) &&
         std::chrono::steady_clock::now() < deadline) {
    (void)front_out.take([&](const void* s) {
      const auto* m = static_cast<const sensor_msgs_msg_dds__CompressedImage_*>(s);
      got_front.push_back(ns_from_time({m->header.stamp.sec, m->header.stamp.nanosec}));
      ids_front.push_back(m->header.frame_id);
    });
    (void)rear_out.take([&](const void* s) {
      const auto* m = static_cast<const sensor_msgs_msg_dds__CompressedImage_*>(s);
      got_rear.push_back(ns_from_time({m->header.stamp.sec, m->header.stamp.nanosec}));
      ids_rear.push_back(m->header.frame_id);
    });
    for (Reader* r : {&front_info, &rear_info}) (void)r->take([&](const void*) { ++infos; });
    (void)faults.take([&](const void* s) {
      const auto* m = static_cast<const diagnostic_msgs_msg_dds__DiagnosticArray_*>(s);
      ++events;
      if (m->status._length == 1 &&
          std::string(m->status._buffer[0].message).rfind("corrupt: brightness/", 0) == 0)
        ++corrupt;
    });
    std::this_thread::sleep_for(
        std::chrono::milliseconds(10));  // polling the readers; not an assertion
  }
  EXPECT_EQ(stop_launch(), 0) << ReadText(dir_ + "/launch.log");
  std::vector<StampNs> want;
  for (int i = 0; i < kFrames; ++i) want.push_back(t0 + i * 83'333'333);
  EXPECT_EQ(got_front, want) << ReadText(dir_ + "/launch.log");
  EXPECT_EQ(got_rear, want);
  EXPECT_EQ(ids_front, std::vector<std::string>(kFrames, "front_optical"));
  EXPECT_EQ(ids_rear, std::vector<std::string>(kFrames, "rear_optical"));
  EXPECT_EQ(infos, 2u * kFrames);
  EXPECT_EQ(events, 2u * kFrames);
  EXPECT_EQ(corrupt, 2u * kFrames)
      << "brightness/mid on both cameras (CAM_FRONT and CAM_FRONT_RIGHT by topic order)";
}

}  // namespace
}  // namespace faultline::ros2dds
