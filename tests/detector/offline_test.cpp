// detector::detect_dataset (`faultline detect`) on a small synthetic dataset: every sample gets an
// entry, the timing count follows the mode, runs repeat exactly, a corruption changes what is seen,
// and an unreadable image fails the run naming its path.
#include "detector/offline.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "dataset/synth.hpp"

namespace faultline::detector {
namespace {

namespace fs = std::filesystem;

class OfflineDetectTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() /
                         ("faultline_offline_detect_" + std::to_string(::getpid())));
    dataset::SynthOptions o;
    o.out_dir = root_->string();
    o.scenes = 2;
    o.seconds = 1.0;
    o.image_width = 400;
    o.image_height = 225;
    auto s = dataset::write_synthetic_dataset(o);
    ASSERT_TRUE(s.is_ok()) << s.status().to_string();
    summary_ = *s;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete root_;
  }
  static OfflineDetectOptions Options() {
    OfflineDetectOptions o;
    o.dataroot = root_->string();
    o.detector.scale = 0.5;
    return o;
  }
  static std::size_t Boxes(const OfflineDetectResult& r) {
    std::size_t n = 0;
    for (const auto& [token, boxes] : r.detections) n += boxes.size();
    return n;
  }
  static fs::path* root_;
  static dataset::SynthSummary summary_;
};
fs::path* OfflineDetectTest::root_ = nullptr;
dataset::SynthSummary OfflineDetectTest::summary_;

TEST_F(OfflineDetectTest, EverySampleHasAnEntryAndEveryFrameATime) {
  auto r = detect_dataset(Options());
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->detections.size(), static_cast<std::size_t>(summary_.samples));
  EXPECT_EQ(r->frame_ms.size(), static_cast<std::size_t>(summary_.camera_frames));  // temporal
  EXPECT_GT(Boxes(*r), 0u);  // the synthetic scenes hold objects the reference detector finds
  auto again = detect_dataset(Options());
  ASSERT_TRUE(again.is_ok());
  ASSERT_EQ(again->detections.size(), r->detections.size());
  for (const auto& [token, boxes] : r->detections) {
    const auto& other = again->detections.at(token);
    ASSERT_EQ(other.size(), boxes.size()) << token;
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      EXPECT_EQ(other[i].center, boxes[i].center) << token;
      EXPECT_EQ(other[i].score, boxes[i].score) << token;
    }
  }
}

TEST_F(OfflineDetectTest, KeyFrameModeTimesEachSampleOnce) {
  auto o = Options();
  o.detector.temporal = false;
  auto r = detect_dataset(o);
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_EQ(r->detections.size(), static_cast<std::size_t>(summary_.samples));
  EXPECT_EQ(r->frame_ms.size(), static_cast<std::size_t>(summary_.samples));
}

TEST_F(OfflineDetectTest, ACorruptionChangesWhatIsDetected) {
  auto o = Options();
  o.corruption = corruption::Corruption::Fog;
  o.severity = 5;
  auto fog = detect_dataset(o);
  ASSERT_TRUE(fog.is_ok()) << fog.status().to_string();
  EXPECT_EQ(fog->detections.size(), static_cast<std::size_t>(summary_.samples));
  auto clean = detect_dataset(Options());
  ASSERT_TRUE(clean.is_ok());
  bool differs = Boxes(*fog) != Boxes(*clean);
  for (const auto& [token, boxes] : fog->detections) {
    const auto& other = clean->detections.at(token);
    if (other.size() != boxes.size()) differs = true;
    for (std::size_t i = 0; !differs && i < boxes.size(); ++i) {
      differs = other[i].center != boxes[i].center || other[i].score != boxes[i].score;
    }
  }
  EXPECT_TRUE(differs);
}

TEST_F(OfflineDetectTest, AnUnreadableImageFailsNamingItsPath) {
  fs::path victim;
  for (const auto& e : fs::recursive_directory_iterator(*root_ / "samples")) {
    if (e.is_regular_file()) {
      victim = e.path();
      break;
    }
  }
  ASSERT_FALSE(victim.empty());
  const fs::path kept = victim.string() + ".kept";
  fs::rename(victim, kept);
  std::ofstream(victim, std::ios::binary) << "not a jpeg";
  auto r = detect_dataset(Options());
  fs::remove(victim);
  fs::rename(kept, victim);
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find(victim.string()), std::string::npos) << r.status().message();
}

}  // namespace
}  // namespace faultline::detector
