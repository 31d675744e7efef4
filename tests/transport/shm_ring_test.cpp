// The shared-memory frame ring: slot reuse, overwrite detection (counted), sizes, stale and live
// files, and the descriptor path through a real publisher and subscriber.
#include "transport/shm_ring.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <fstream>
#include <numeric>

#include "common/config.hpp"
#include "test_util.hpp"
#include "transport/typed.hpp"

namespace faultline::transport {
namespace {

class ShmRingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-shm-test-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
    path_ = dir_ + "/ring";
  }
  void TearDown() override {
    ::unlink(path_.c_str());
    ::rmdir(dir_.c_str());
  }
  ShmRingConfig Config(std::uint32_t slots, std::uint64_t slot_bytes) const {
    ShmRingConfig c;
    c.path = path_;
    c.slot_count = slots;
    c.slot_bytes = slot_bytes;
    return c;
  }
  // A frame of `n` bytes whose content names its index.
  static std::vector<std::uint8_t> Frame(int index, std::size_t n = 16) {
    std::vector<std::uint8_t> f(n);
    std::iota(f.begin(), f.end(), static_cast<std::uint8_t>(index * 7));
    return f;
  }
  ShmSlotRef Write(ShmRingWriter& w, int index, std::size_t n = 16) {
    const auto f = Frame(index, n);
    auto ref = w.write(f.data(), f.size());
    EXPECT_TRUE(ref.is_ok()) << ref.status().message();
    return ref.is_ok() ? *ref : ShmSlotRef{};
  }
  bool Exists() const {
    struct stat st {};
    return ::stat(path_.c_str(), &st) == 0;
  }
  std::string dir_, path_;
};

TEST_F(ShmRingTest, WrapAroundReusesSlotsInOrderAndCountsOverwrittenFrames) {
  ShmRingWriter w(Config(3, 16));
  std::vector<ShmSlotRef> refs;
  for (int i = 0; i < 7; ++i) refs.push_back(Write(w, i));
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(refs[i].slot, static_cast<std::uint32_t>(i % 3));
    EXPECT_EQ(refs[i].sequence, static_cast<std::uint64_t>(2 * i + 2));
  }
  auto reader = ShmRingReader::open(path_);
  ASSERT_TRUE(reader.is_ok()) << reader.status().message();
  for (int i = 0; i < 4; ++i) {  // overwritten by frames 3..6
    auto v = reader->acquire(refs[i]);
    ASSERT_FALSE(v.is_ok());
    EXPECT_EQ(v.status().code(), StatusCode::kNotFound);
    EXPECT_NE(v.status().message().find("overwritten before it was read"), std::string::npos);
  }
  for (int i = 4; i < 7; ++i) {
    auto v = reader->acquire(refs[i]);
    ASSERT_TRUE(v.is_ok()) << v.status().message();
    EXPECT_EQ(std::vector<std::uint8_t>(v->data, v->data + v->size_bytes), Frame(i));
    EXPECT_TRUE(reader->intact(*v));
  }
  EXPECT_EQ(reader->overwritten_before_read(), 4u);
  EXPECT_EQ(reader->overwritten_during_use(), 0u);
  EXPECT_EQ(w.frames_written(), 7u);
}

TEST_F(ShmRingTest, OverwriteWhileInUseIsCounted) {
  ShmRingWriter w(Config(2, 16));
  const ShmSlotRef first = Write(w, 0);
  auto reader = ShmRingReader::open(path_);
  ASSERT_TRUE(reader.is_ok());
  auto v = reader->acquire(first);
  ASSERT_TRUE(v.is_ok());
  Write(w, 1);  // the other slot: the frame in use is untouched
  EXPECT_TRUE(reader->intact(*v));
  Write(w, 2);  // slot 0 again
  EXPECT_FALSE(reader->intact(*v));
  EXPECT_EQ(reader->overwritten_during_use(), 1u);
  EXPECT_EQ(std::vector<std::uint8_t>(v->data, v->data + v->size_bytes), Frame(2));
}

TEST_F(ShmRingTest, FrameBiggerThanASlotIsRefusedCountedAndLeavesTheRingAsItWas) {
  ShmRingWriter w(Config(4, 16));
  const auto big = Frame(9, 17);
  auto r = w.write(big.data(), big.size());
  ASSERT_FALSE(r.is_ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("frame of 17 bytes refused by shm ring " + path_),
            std::string::npos);
  EXPECT_NE(r.status().message().find("slots hold 16 bytes"), std::string::npos);
  EXPECT_EQ(w.oversize_refused(), 1u);
  EXPECT_EQ(w.frames_written(), 0u);
  EXPECT_EQ(Write(w, 0).slot, 0u);  // the next frame takes the first slot
}

TEST_F(ShmRingTest, SizesOfFileSlotsAndFrames) {
  ShmRingWriter w(Config(5, 5000));
  struct stat st {};
  ASSERT_EQ(::stat(path_.c_str(), &st), 0);
  // Header page + 5 slots of (64-byte slot header + 5000 bytes) rounded up to pages.
  EXPECT_EQ(st.st_size, static_cast<off_t>(kShmHeaderBytes + 5 * 8192));
  auto reader = ShmRingReader::open(path_);
  ASSERT_TRUE(reader.is_ok());
  EXPECT_EQ(reader->slot_count(), 5u);
  EXPECT_EQ(reader->slot_bytes(), 5000u);
  EXPECT_EQ(reader->ring_id(), w.ring_id());
  const ShmSlotRef empty = Write(w, 0, 0);
  const ShmSlotRef full = Write(w, 1, 5000);
  EXPECT_EQ(full.offset, kShmHeaderBytes + 8192 + kShmSlotHeaderBytes);
  EXPECT_EQ(full.offset % 64, 0u);  // pixels start cache-line aligned
  auto e = reader->acquire(empty);
  ASSERT_TRUE(e.is_ok());
  EXPECT_EQ(e->size_bytes, 0u);
  auto f = reader->acquire(full);
  ASSERT_TRUE(f.is_ok());
  EXPECT_EQ(std::vector<std::uint8_t>(f->data, f->data + f->size_bytes), Frame(1, 5000));
  ShmSlotRef wrong = full;
  wrong.size_bytes = 5001;
  EXPECT_EQ(reader->acquire(wrong).status().code(), StatusCode::kCorruptData);
  wrong = full;
  wrong.offset += 1;
  EXPECT_EQ(reader->acquire(wrong).status().code(), StatusCode::kCorruptData);
}

TEST_F(ShmRingTest, BadConfigurationAndBadFilesNameTheProblem) {
  EXPECT_THROW(ShmRingWriter(Config(1, 16)), ConfigError);
  EXPECT_THROW(ShmRingWriter(Config(4, 0)), ConfigError);
  EXPECT_EQ(ShmRingReader::open(path_).status().code(), StatusCode::kNotFound);
  std::ofstream(path_) << std::string(8192, 'x');
  auto r = ShmRingReader::open(path_);
  EXPECT_EQ(r.status().code(), StatusCode::kCorruptData);
  EXPECT_NE(r.status().message().find("bad magic"), std::string::npos);
}

TEST_F(ShmRingTest, TheWriterRemovesItsFileAtExit) {
  {
    ShmRingWriter w(Config(2, 16));
    EXPECT_TRUE(Exists());
  }
  EXPECT_FALSE(Exists());
}

TEST_F(ShmRingTest, StaleFileOfAKilledWriterIsReplacedAndOldReadersSeeTheRestart) {
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // a writer killed before it could clean up
    ShmRingWriter w(Config(2, 16));
    ::raise(SIGKILL);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(Exists());
  auto old_reader = ShmRingReader::open(path_);
  ASSERT_TRUE(old_reader.is_ok());
  ShmRingWriter w(Config(2, 16));  // does not throw: the old writer is gone
  EXPECT_NE(w.ring_id(), old_reader->ring_id());
  const ShmSlotRef ref = Write(w, 0);
  auto v = old_reader->acquire(ref);
  EXPECT_EQ(v.status().code(), StatusCode::kNotFound);
  EXPECT_NE(v.status().message().find("recreated"), std::string::npos);
  auto fresh = ShmRingReader::open(path_);
  ASSERT_TRUE(fresh.is_ok());
  EXPECT_TRUE(fresh->acquire(ref).is_ok());
}

TEST_F(ShmRingTest, RingOfALiveWriterIsNotTaken) {
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ShmRingWriter w(Config(2, 16));
    const char c = 'r';
    (void)!::write(ready[1], &c, 1);
    ::pause();  // until the parent kills it
    ::_exit(0);
  }
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1);
  try {
    ShmRingWriter w(Config(2, 16));
    ADD_FAILURE() << "a live writer's ring was taken over";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("in use by the running process " + std::to_string(child)),
              std::string::npos)
        << e.what();
  }
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  ::close(ready[0]);
  ::close(ready[1]);
  EXPECT_TRUE(Exists());  // the refused writer did not remove the live one's file
}

TEST_F(ShmRingTest, PathIsDerivedFromNodeAndEndpoint) {
  const std::string a = shm_ring_path("/dev/shm", "fault_injector", "ipc:///tmp/a/frames");
  EXPECT_EQ(a.rfind("/dev/shm/faultline-fault_injector-", 0), 0u);
  EXPECT_EQ(a.size(), std::string("/dev/shm/faultline-fault_injector-").size() + 16 + 5);
  EXPECT_NE(a, shm_ring_path("/dev/shm", "fault_injector", "ipc:///tmp/b/frames"));
  EXPECT_EQ(shm_ring_path("/d", "a/b c", "x").find("a_b_c"), std::string("/d/faultline-").size());
}

TEST_F(ShmRingTest, DescriptorsTravelOnTheSocketAndTheReaderMapsThePixels) {
  PublisherConfig pc;
  pc.endpoint = testing::unique_ipc("shm");
  pc.snd_hwm = 16;
  Publisher pub(pc);
  SubscriberConfig sc;
  sc.endpoints = {pub.endpoint()};
  sc.topics = {"/faulty/"};
  sc.rcv_hwm = 16;
  RawSubscriber sub(sc);
  ASSERT_TRUE(pub.wait_for_subscribers("/faulty/cam_front/image_raw", 1, 5 * kNsPerSec).is_ok());
  ShmRingWriter ring(Config(2, 4 * 2 * 3));
  ShmCameraReader reader;
  for (int i = 0; i < 3; ++i) {
    msgs::CameraFrame h;
    h.set_encoding("bgr8");
    h.set_width(4);
    h.set_height(2);
    h.set_step(12);
    h.mutable_header()->set_seq(static_cast<std::uint64_t>(i + 1));
    const auto pixels = std::make_shared<const std::vector<std::uint8_t>>(Frame(i, 24));
    ASSERT_TRUE(
        send_camera_frame_shm(pub, ring, "/faulty/cam_front/image_raw", h, Payload::of(pixels))
            .is_ok());
    EXPECT_FALSE(h.has_shm());  // the caller's header is left without the descriptor
  }
  const std::uint64_t expected_overwritten = 1;  // 3 frames in 2 slots, read after all were sent
  for (int i = 0; i < 3; ++i) {
    auto msg = sub.receive(5 * kNsPerSec);
    ASSERT_TRUE(msg.is_ok()) << msg.status().message();
    EXPECT_FALSE(msg->has_payload());
    const auto plain = parse_camera_frame(*msg);
    EXPECT_EQ(plain.status().code(), StatusCode::kUnsupported);
    EXPECT_NE(plain.status().message().find("ShmCameraReader"), std::string::npos);
    auto v = reader.read(*msg);
    if (i == 0) {
      EXPECT_EQ(v.status().code(), StatusCode::kNotFound) << v.status().message();
      continue;
    }
    ASSERT_TRUE(v.is_ok()) << v.status().message();
    EXPECT_EQ(v->header.header().seq(), static_cast<std::uint64_t>(i + 1));
    EXPECT_EQ(std::vector<std::uint8_t>(v->payload, v->payload + v->payload_size), Frame(i, 24));
    EXPECT_TRUE(reader.intact(*v));
  }
  EXPECT_EQ(reader.overwritten(), expected_overwritten);
  msgs::CameraFrame big;
  big.set_encoding("bgr8");
  const auto too_big = std::make_shared<const std::vector<std::uint8_t>>(25);
  EXPECT_EQ(
      send_camera_frame_shm(pub, ring, "/faulty/cam_front/image_raw", big, Payload::of(too_big))
          .code(),
      StatusCode::kInvalidArgument);
  EXPECT_EQ(ring.oversize_refused(), 1u);
}

}  // namespace
}  // namespace faultline::transport
