#include "runtime/results_store.hpp"

#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "scoring/submission.hpp"

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
  std::string ReadText() const {
    std::ifstream in(Out());
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  rapidjson::Document Read() const {
    rapidjson::Document doc;
    doc.Parse<rapidjson::kParseNanAndInfFlag | rapidjson::kParseFullPrecisionFlag>(
        ReadText().c_str());
    EXPECT_FALSE(doc.HasParseError());
    return doc;
  }
  // The output read by the scorer's own reader (every box checked, as `faultline score` does).
  Status Scorable() const {
    auto sub = scoring::parse_submission(ReadText(), Out(), scoring::SubmissionScope{});
    return sub.is_ok() ? Status::ok() : sub.status();
  }
  static void ExpectReason(const AddDetectionsReport& report, const std::string& fragment) {
    for (const auto& r : report.reasons) {
      if (r.find(fragment) != std::string::npos) return;
    }
    ADD_FAILURE() << "no refusal mentions '" << fragment << "'";
  }
  std::string dir_;
};

TEST_F(ResultsStoreTest, FinalizeWritesSubmissionFormatWithEmptySamples) {
  ResultsStore store(Out(), Journal());
  ASSERT_TRUE(store.add_detections(Array("s1", 2)).journal.is_ok());
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
    ASSERT_TRUE(store.add_detections(Array("s1", 1)).journal.is_ok());
    ASSERT_TRUE(store.add_sample("s2").is_ok());
  }  // "crash": never finalized
  std::ofstream(Journal(), std::ios::app) << R"({"kind":"detections","sample_token":"s3","bo)";
  ResultsStore again(Out(), Journal());
  auto r = again.recover();
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r->lines, 2u);
  EXPECT_EQ(r->bad_lines, 1u);  // the torn line is counted, not dropped silently
  EXPECT_NE(r->first_bad.find("line 4: not valid JSON"), std::string::npos) << r->first_bad;
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
  ASSERT_TRUE(store.add_detections(Array("s1", 3)).journal.is_ok());
  ASSERT_TRUE(store.add_detections(Array("s1", 1)).journal.is_ok());
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

TEST_F(ResultsStoreTest, BoxesTheScorerRejectsAreRefusedAndTheRestKept) {
  auto d = Array("s1", 5);
  d.mutable_detections(1)->set_detection_score(NAN);
  d.mutable_detections(2)->set_detection_name("Car");
  d.mutable_detections(3)->set_translation(0, INFINITY);
  d.mutable_detections(4)->set_detection_score(-0.1);
  ResultsStore store(Out(), Journal());
  const AddDetectionsReport report = store.add_detections(d);
  EXPECT_FALSE(report.array_rejected);
  EXPECT_EQ(report.boxes_kept, 1u);
  EXPECT_EQ(report.boxes_rejected, 4u);
  ASSERT_EQ(report.reasons.size(), 4u);
  ExpectReason(report, "results['s1'][1]: 'detection_score' is NaN");
  ExpectReason(report, "results['s1'][2]: Error: Unknown detection_name Car");
  ExpectReason(report, "results['s1'][3]: 'translation'[0] is Infinity");
  ExpectReason(report, "results['s1'][4]: negative 'detection_score'");
  ASSERT_TRUE(store.add_sample("s1").is_ok());
  ASSERT_TRUE(store.finalize("{}").is_ok());
  EXPECT_EQ(Read()["results"]["s1"].Size(), 1u);
  const Status scorable = Scorable();
  EXPECT_TRUE(scorable.is_ok()) << scorable.message();
}

TEST_F(ResultsStoreTest, ArrayOverFiveHundredBoxesIsRefusedWhole) {
  ResultsStore store(Out(), Journal());
  ASSERT_TRUE(store.add_detections(Array("s1", 2)).journal.is_ok());
  const AddDetectionsReport report = store.add_detections(Array("s1", 501));
  EXPECT_TRUE(report.array_rejected);
  EXPECT_EQ(report.boxes_kept, 0u);
  EXPECT_TRUE(store.add_detections(Array("s2", 501)).array_rejected);
  EXPECT_FALSE(store.has_detections("s2"));
  EXPECT_TRUE(store.answered("s2"));  // the sink does not wait for another array of s2
  ExpectReason(report, "results['s1']: Error: Only <= 500 boxes per sample allowed! (found 501)");
  ASSERT_TRUE(store.finalize("{}").is_ok());
  EXPECT_EQ(Read()["results"]["s1"].Size(), 2u);  // the earlier array stands
  EXPECT_TRUE(Scorable().is_ok());
  ResultsStore recovered(Out(), Journal());  // the refused array was not journaled
  auto r = recovered.recover();
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r->lines, 1u);
  EXPECT_EQ(r->bad_lines, 0u);
}

TEST_F(ResultsStoreTest, ArrayWithoutSampleTokenIsRefused) {
  ResultsStore store(Out(), Journal());
  const AddDetectionsReport report = store.add_detections(Array("", 1));
  EXPECT_TRUE(report.array_rejected);
  ExpectReason(report, "empty sample_token");
  EXPECT_EQ(store.detection_count(), 0u);
}

TEST_F(ResultsStoreTest, TokensOutsideTheSplitAreRefusedWhenTheSplitIsKnown) {
  ResultsStore store(Out(), Journal());
  store.set_valid_samples({"s1", "s2"}, "split 'unit'");
  ASSERT_TRUE(store.add_sample("s1").is_ok());
  EXPECT_EQ(store.add_sample("bogus").code(), StatusCode::kInvalidArgument);
  ASSERT_TRUE(store.add_detections(Array("s1", 1)).journal.is_ok());
  const AddDetectionsReport report = store.add_detections(Array("bogus", 1));
  EXPECT_TRUE(report.array_rejected);
  ExpectReason(report, "results['bogus']: sample token not in split 'unit'");
  ASSERT_TRUE(store.finalize("{}").is_ok());
  const auto doc = Read();
  EXPECT_EQ(doc["results"].MemberCount(), 1u);
  EXPECT_TRUE(doc["results"].HasMember("s1"));
}

TEST_F(ResultsStoreTest, WithoutASplitAnyTokenIsKept) {
  ResultsStore store(Out(), Journal());
  ASSERT_TRUE(store.add_sample("s1").is_ok());
  ASSERT_TRUE(store.add_detections(Array("s1", 1)).journal.is_ok());
  ASSERT_TRUE(store.add_detections(Array("s2", 1)).journal.is_ok());
  ASSERT_TRUE(store.finalize("{}").is_ok());
  EXPECT_EQ(Read()["results"].MemberCount(), 2u);
}

TEST_F(ResultsStoreTest, UnreadableJournalLinesAreCountedAndNamed) {
  {
    ResultsStore store(Out(), Journal());
    ASSERT_TRUE(store.add_sample("s1").is_ok());
  }
  std::ofstream(Journal(), std::ios::app) << "garbage\n"
                                          << R"({"kind":"detections","sample_token":"s2"})"
                                          << "\n"
                                          << R"({"kind":"sample","sample_token":"s3"})"
                                          << "\n";
  ResultsStore again(Out(), Journal());
  auto r = again.recover();
  ASSERT_TRUE(r.is_ok());
  EXPECT_EQ(r->lines, 2u);
  EXPECT_EQ(r->bad_lines, 2u);
  EXPECT_NE(r->first_bad.find("line 3"), std::string::npos) << r->first_bad;  // after "run"
}

TEST_F(ResultsStoreTest, JournalRoundTripKeepsDoublesBitIdentical) {
  // Values whose last digit changed through the journal (RapidJSON's default, lossy number parser)
  // or whose written text was not the shortest (Grisu2): 17.735607021569707 for ...706.
  const std::vector<double> values = {17.735607021569706,
                                      -12.195538540161131,
                                      0.035484969720691824,
                                      -0.043900158474224425,
                                      5e-324,
                                      1.7976931348623157e308};
  msgs::DetectionArray d = Array("s1", 1);
  auto* box = d.mutable_detections(0);
  box->set_translation(0, values[0]);
  box->set_translation(1, values[1]);
  box->set_translation(2, values[4]);
  box->set_size(0, values[2]);
  box->set_velocity(0, values[3]);
  box->add_velocity(values[5]);
  box->set_detection_score(values[2]);
  {
    ResultsStore store(Out(), Journal());
    ASSERT_TRUE(store.add_detections(d).journal.is_ok());
  }  // "crash": the results come from the journal alone
  ResultsStore again(Out(), Journal());
  ASSERT_TRUE(again.recover().is_ok());
  ASSERT_TRUE(again.finalize("{}").is_ok());
  const std::string text = ReadText();
  EXPECT_NE(text.find("17.735607021569706"), std::string::npos) << text;
  const auto doc = Read();
  const auto& out = doc["results"]["s1"][0];
  auto same_bits = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  EXPECT_TRUE(same_bits(out["translation"][0].GetDouble(), values[0]));
  EXPECT_TRUE(same_bits(out["translation"][1].GetDouble(), values[1]));
  EXPECT_TRUE(same_bits(out["translation"][2].GetDouble(), values[4]));
  EXPECT_TRUE(same_bits(out["size"][0].GetDouble(), values[2]));
  EXPECT_TRUE(same_bits(out["velocity"][0].GetDouble(), values[3]));
  EXPECT_TRUE(same_bits(out["velocity"][1].GetDouble(), values[5]));
  EXPECT_TRUE(same_bits(out["detection_score"].GetDouble(), values[2]));
}

TEST_F(ResultsStoreTest, JournalOfTheSameRunIsResumed) {
  const std::map<std::string, std::string> run = {{"dataset", "mini"}, {"injector", "fog/easy"}};
  {
    ResultsStore store(Out(), Journal());
    store.set_run_identity(run);
    ASSERT_TRUE(store.add_detections(Array("s1", 1)).journal.is_ok());
  }
  ResultsStore again(Out(), Journal());
  again.set_run_identity(run);
  auto r = again.recover();
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ(r->lines, 1u);
  EXPECT_TRUE(again.has_detections("s1"));
  ASSERT_TRUE(again.add_sample("s2").is_ok());  // appends without a second "run" line
  ResultsStore third(Out(), Journal());
  third.set_run_identity(run);
  auto r3 = third.recover();
  ASSERT_TRUE(r3.is_ok()) << r3.status().message();
  EXPECT_EQ(r3->lines, 2u);
}

TEST_F(ResultsStoreTest, JournalOfAnotherRunIsRefusedNamingBoth) {
  {
    ResultsStore store(Out(), Journal());
    store.set_run_identity({{"dataset", "mini"}, {"injector", "clean"}});
    ASSERT_TRUE(store.add_detections(Array("s1", 1)).journal.is_ok());
  }
  ResultsStore later(Out(), Journal());
  later.set_run_identity({{"dataset", "mini"}, {"injector", "camera_crash/hard"}});
  auto r = later.recover();
  ASSERT_FALSE(r.is_ok());
  const std::string& msg = r.status().message();
  EXPECT_NE(msg.find(Journal() + ": written by run {dataset=mini, injector=clean}, but this run is "
                                 "{dataset=mini, injector=camera_crash/hard}"),
            std::string::npos)
      << msg;
  EXPECT_FALSE(later.has_detections("s1"));
}

TEST_F(ResultsStoreTest, JournalWithoutIdentityIsRefusedByARunWithOne) {
  std::ofstream(Journal()) << R"({"kind":"sample","sample_token":"s1"})"
                           << "\n";  // older sink
  ResultsStore store(Out(), Journal());
  store.set_run_identity({{"dataset", "mini"}});
  auto r = store.recover();
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("unknown identity"), std::string::npos)
      << r.status().message();
}

}  // namespace
}  // namespace faultline::runtime
