#include "runtime/results_store.hpp"

#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace faultline::runtime {
namespace {

class ResultsStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/faultline-results-XXXXXX";
    dir_ = ::mkdtemp(tmpl);
  }
  void TearDown() override { std::system(("rm -rf " + dir_).c_str()); }
  std::string Out() const { return dir_ + "/results.json"; }
  std::string Journal() const { return dir_ + "/results.json.journal"; }
  static msgs::DetectionArray Array(const std::string& token, int boxes) {
    msgs::DetectionArray d;
    d.set_sample_token(token);
    d.set_detector("fake");
    for (int i = 0; i < boxes; ++i) {
      auto* b = d.add_detections();
      for (double v : {1.0 + i, 2.0, 3.0}) b->add_translation(v);
      for (double v : {1.5, 4.0, 1.7}) b->add_size(v);
      for (double v : {1.0, 0.0, 0.0, 0.0}) b->add_rotation(v);
      b->add_velocity(NAN);  // allowed by the devkit; second component padded with 0
      b->set_detection_name("car");
      b->set_detection_score(0.5);
      b->set_attribute_name("vehicle.moving");
    }
    return d;
  }
  rapidjson::Document Read() const {
    std::ifstream in(Out());
    std::stringstream ss;
    ss << in.rdbuf();
    rapidjson::Document doc;
    doc.Parse<rapidjson::kParseNanAndInfFlag>(ss.str().c_str());
    EXPECT_FALSE(doc.HasParseError());
    return doc;
  }
  std::string dir_;
};

TEST_F(ResultsStoreTest, FinalizeWritesSubmissionFormatWithEmptySamples) {
  ResultsStore store(Out(), Journal());
  ASSERT_TRUE(store.add_detections(Array("s1", 2)).is_ok());
  ASSERT_TRUE(store.add_sample("s1").is_ok());
  ASSERT_TRUE(store.add_sample("s2").is_ok());
  ASSERT_TRUE(store.finalize(R"({"run":"unit"})").is_ok());
  const auto doc = Read();
  EXPECT_TRUE(doc["meta"]["use_camera"].GetBool());
  EXPECT_FALSE(doc["meta"]["use_lidar"].GetBool());
  EXPECT_STREQ(doc["meta"]["run"].GetString(), "unit");
  ASSERT_EQ(doc["results"]["s1"].Size(), 2u);
  EXPECT_EQ(doc["results"]["s2"].Size(), 0u);
  const auto& box = doc["results"]["s1"][0];
  EXPECT_STREQ(box["sample_token"].GetString(), "s1");
  EXPECT_EQ(box["translation"].Size(), 3u);
  EXPECT_EQ(box["rotation"].Size(), 4u);
  ASSERT_EQ(box["velocity"].Size(), 2u);
  EXPECT_TRUE(std::isnan(box["velocity"][0].GetDouble()));
  EXPECT_EQ(box["velocity"][1].GetDouble(), 0.0);
  EXPECT_STREQ(box["attribute_name"].GetString(), "vehicle.moving");
}

TEST_F(ResultsStoreTest, RestartRecoversFromJournalAndSkipsTornLine) {
  {
    ResultsStore store(Out(), Journal());
    ASSERT_TRUE(store.add_detections(Array("s1", 1)).is_ok());
    ASSERT_TRUE(store.add_sample("s2").is_ok());
  }  // "crash": never finalized
  std::ofstream(Journal(), std::ios::app) << R"({"kind":"detections","sample_token":"s3","bo)";
  ResultsStore again(Out(), Journal());
  auto r = again.recover();
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(*r, 2u);
  EXPECT_TRUE(again.has_detections("s1"));
  EXPECT_FALSE(again.has_detections("s3"));
  EXPECT_EQ(again.detector(), "fake");
  ASSERT_TRUE(again.finalize("{}").is_ok());
  const auto doc = Read();
  EXPECT_EQ(doc["results"]["s1"].Size(), 1u);
  EXPECT_EQ(doc["results"]["s2"].Size(), 0u);
  EXPECT_FALSE(doc["results"].HasMember("s3"));
}

TEST_F(ResultsStoreTest, LaterArrayForSameSampleReplacesEarlier) {
  ResultsStore store(Out(), Journal());
  ASSERT_TRUE(store.add_detections(Array("s1", 3)).is_ok());
  ASSERT_TRUE(store.add_detections(Array("s1", 1)).is_ok());
  ASSERT_TRUE(store.finalize("{}").is_ok());
  EXPECT_EQ(Read()["results"]["s1"].Size(), 1u);
  ResultsStore recovered(Out(), Journal());
  ASSERT_TRUE(recovered.recover().is_ok());
  EXPECT_EQ(recovered.detection_count(), 1u);
}

TEST_F(ResultsStoreTest, RemoveJournalStartsFresh) {
  ResultsStore store(Out(), Journal());
  ASSERT_TRUE(store.add_sample("s1").is_ok());
  ASSERT_TRUE(store.remove_journal().is_ok());
  EXPECT_NE(::access(Journal().c_str(), F_OK), 0);
}

TEST_F(ResultsStoreTest, UnwritableOutputIsAnIoError) {
  ResultsStore store(dir_ + "/missing/dir/results.json", Journal());
  EXPECT_EQ(store.finalize("{}").code(), StatusCode::kIoError);
}

}  // namespace
}  // namespace faultline::runtime
