// Bad submissions and datasets: each gives a clear error naming the place, writes no metrics, and
// the CLI exits non-zero. Also the defined behaviour where the devkit crashes (no box at all).
#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>

#include <cstdlib>
#include <filesystem>
#include <limits>
#include <set>

#include "scoring/evaluate.hpp"
#include "scoring/submission.hpp"
#include "test_util.hpp"

namespace faultline::scoring {
namespace {

using testing::golden_dir;
using testing::read_text;
using testing::TempDir;
using testing::write_text;

class BadInputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string text = read_text(golden_dir() + "/predictions/perfect.json");
    doc_.Parse<rapidjson::kParseNanAndInfFlag | rapidjson::kParseFullPrecisionFlag>(text.c_str(),
                                                                                    text.size());
    ASSERT_FALSE(doc_.HasParseError());
    first_token_ = doc_["results"].MemberBegin()->name.GetString();
  }
  rapidjson::Value& FirstBox() { return doc_["results"].MemberBegin()->value[0]; }

  std::string Write(const std::string& name) {
    rapidjson::StringBuffer buf;
    rapidjson::Writer<rapidjson::StringBuffer, rapidjson::UTF8<>, rapidjson::UTF8<>,
                      rapidjson::CrtAllocator, rapidjson::kWriteNanAndInfFlag>
        w(buf);
    doc_.Accept(w);
    const std::string path = dir_.file(name);
    write_text(path, buf.GetString());
    return path;
  }

  // Expects a failure whose message contains every fragment, and no metrics file.
  void ExpectRejected(const std::string& results, std::vector<std::string> fragments,
                      const std::string& dataroot = golden_dir() + "/dataset") {
    EvalOptions opts;
    opts.results_path = results;
    opts.dataroot = dataroot;
    opts.version = "v1.0-mini";
    opts.eval_set = "mini_val";
    opts.output_dir = dir_.file("out");
    auto r = evaluate_detection(opts, nullptr);
    ASSERT_FALSE(r.is_ok());
    for (const auto& f : fragments) {
      EXPECT_NE(r.status().message().find(f), std::string::npos)
          << "'" << f << "' not in: " << r.status().message();
    }
    EXPECT_FALSE(std::filesystem::exists(opts.output_dir));
  }

  // Scores a submission of mini_val; the outcome or its error.
  Result<EvalOutcome> Score(const std::string& results,
                            std::uint64_t max_bytes = kDefaultMaxResultsBytes) {
    EvalOptions opts;
    opts.results_path = results;
    opts.dataroot = golden_dir() + "/dataset";
    opts.version = "v1.0-mini";
    opts.eval_set = "mini_val";
    opts.max_results_bytes = max_bytes;
    return evaluate_detection(opts, nullptr);
  }
  // perfect.json with `extra` inserted as the first members of the top-level object.
  static std::string PerfectWithLeadingMembers(const std::string& extra) {
    std::string text = read_text(golden_dir() + "/predictions/perfect.json");
    const std::size_t brace = text.find('{');
    return text.substr(0, brace + 1) + extra + "," + text.substr(brace + 1);
  }

  TempDir dir_{"bad_input"};
  rapidjson::Document doc_;
  std::string first_token_;
};

TEST_F(BadInputTest, MalformedJsonNamesFileAndOffset) {
  std::string text = read_text(golden_dir() + "/predictions/perfect.json");
  text.resize(5000);
  const std::string path = dir_.file("truncated.json");
  write_text(path, text);
  ExpectRejected(path, {path, "offset 5000"});
}

TEST_F(BadInputTest, NanTranslationNamesSampleAndBox) {
  FirstBox()["translation"][1].SetDouble(std::numeric_limits<double>::quiet_NaN());
  ExpectRejected(Write("nan.json"), {first_token_, "[0]", "'translation' contains NaN"});
}

TEST_F(BadInputTest, UnknownClassIsRejected) {
  FirstBox()["detection_name"].SetString("Car");
  ExpectRejected(Write("car.json"), {first_token_, "Unknown detection_name Car"});
}

TEST_F(BadInputTest, UnknownAttributeIsRejected) {
  FirstBox()["attribute_name"].SetString("vehicle.flying");
  ExpectRejected(Write("attr.json"), {first_token_, "Unknown attribute_name vehicle.flying"});
}

TEST_F(BadInputTest, MoreThan500BoxesIsRejected) {
  auto& list = doc_["results"].MemberBegin()->value;
  rapidjson::Value box(list[0], doc_.GetAllocator());
  while (list.Size() <= 500)
    list.PushBack(rapidjson::Value(box, doc_.GetAllocator()), doc_.GetAllocator());
  ExpectRejected(Write("many.json"), {first_token_, "Only <= 500 boxes per sample allowed", "501"});
}

TEST_F(BadInputTest, MissingSampleOfPredefinedSplitIsRejected) {
  doc_["results"].RemoveMember(first_token_.c_str());
  ExpectRejected(Write("missing.json"),
                 {"Samples in split doesn't match", "missing", first_token_});
}

TEST_F(BadInputTest, ExtraSampleOfPredefinedSplitIsRejected) {
  doc_["results"].AddMember("0000000000000000000000000000beef",
                            rapidjson::Value(rapidjson::kArrayType), doc_.GetAllocator());
  ExpectRejected(Write("extra.json"),
                 {"Samples in split doesn't match", "0000000000000000000000000000beef"});
}

TEST_F(BadInputTest, NegativeScoreIsRejected) {
  FirstBox()["detection_score"].SetDouble(-0.2);
  ExpectRejected(Write("neg.json"), {first_token_, "negative 'detection_score'"});
}

TEST_F(BadInputTest, InfinityTranslationNamesSampleBoxAndField) {
  FirstBox()["translation"][0].SetDouble(std::numeric_limits<double>::infinity());
  ExpectRejected(Write("inf.json"), {first_token_, "[0]: 'translation'[0] is Infinity"});
}

TEST_F(BadInputTest, InfinityScoreIsRejected) {
  FirstBox()["detection_score"].SetDouble(std::numeric_limits<double>::infinity());
  ExpectRejected(Write("inf_score.json"), {first_token_, "'detection_score' is Infinity"});
}

TEST_F(BadInputTest, NegativeInfinityVelocityIsRejectedThoughNanIsAllowed) {
  FirstBox()["velocity"][0].SetDouble(std::numeric_limits<double>::quiet_NaN());
  FirstBox()["velocity"][1].SetDouble(-std::numeric_limits<double>::infinity());
  ExpectRejected(Write("inf_vel.json"), {first_token_, "'velocity'[1] is -Infinity"});
}

TEST_F(BadInputTest, ScoreAboveOneIsAcceptedAsByTheDevkit) {
  FirstBox()["detection_score"].SetDouble(1.5);  // spec §1: float(), range not checked
  auto r = Score(Write("above_one.json"));
  ASSERT_TRUE(r.is_ok()) << r.status().message();
}

TEST_F(BadInputTest, LastOfTwoResultsKeysWinsAsInPython) {
  const std::string path = dir_.file("two_results.json");
  write_text(path, PerfectWithLeadingMembers(R"("results": {"not-a-token": 5})"));
  auto twice = Score(path);
  ASSERT_TRUE(twice.is_ok()) << twice.status().message();
  auto once = Score(golden_dir() + "/predictions/perfect.json");
  ASSERT_TRUE(once.is_ok()) << once.status().message();
  EXPECT_EQ(twice->metrics.nd_score, once->metrics.nd_score);
  EXPECT_EQ(twice->samples, once->samples);
}

TEST_F(BadInputTest, LastResultsKeyIsTheOneValidated) {
  std::string text = read_text(golden_dir() + "/predictions/perfect.json");
  text.insert(text.rfind('}'), R"(, "results": {"not-a-token": 5})");
  const std::string path = dir_.file("bad_last_results.json");
  write_text(path, text);
  ExpectRejected(path, {"results['not-a-token']", "must be a list of boxes"});
}

TEST_F(BadInputTest, RepeatedSampleKeyKeepsLastListAtFirstPlace) {
  rapidjson::Value& list = doc_["results"].MemberBegin()->value;
  rapidjson::Value saved(list, doc_.GetAllocator());
  list.Clear();
  auto emptied = Score(Write("emptied_sample.json"));  // the first sample's list emptied in place
  ASSERT_TRUE(emptied.is_ok()) << emptied.status().message();
  list = saved;
  rapidjson::Value key(first_token_.c_str(), doc_.GetAllocator());
  doc_["results"].AddMember(key, rapidjson::Value(rapidjson::kArrayType), doc_.GetAllocator());
  auto repeated =
      Score(Write("repeated_sample.json"));  // ... or emptied by a repeated key at the end
  ASSERT_TRUE(repeated.is_ok()) << repeated.status().message();
  EXPECT_EQ(repeated->metrics.nd_score, emptied->metrics.nd_score);
  EXPECT_EQ(repeated->pred_counts.original, emptied->pred_counts.original);
  EXPECT_EQ(repeated->samples, emptied->samples);
}

TEST_F(BadInputTest, RepeatedBoxFieldKeepsLastValue) {
  FirstBox()["detection_score"].SetDouble(std::numeric_limits<double>::quiet_NaN());
  FirstBox().AddMember("detection_score", 0.5, doc_.GetAllocator());
  auto r = Score(Write("repeated_field.json"));
  ASSERT_TRUE(r.is_ok()) << r.status().message();
}

TEST_F(BadInputTest, RepeatedMetaKeysKeepLastValues) {
  doc_.RemoveMember("meta");
  const std::string path = Write("two_meta.json");
  std::string text = read_text(path);
  text.insert(
      text.find('{') + 1,
      R"("meta": {"first": 1}, "meta": {"use_camera": false, "x": 1, "use_camera": true},)");
  write_text(path, text);
  auto r = Score(path);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  const rapidjson::Value& meta = *r->meta;
  ASSERT_TRUE(meta.IsObject());
  EXPECT_EQ(meta.MemberCount(), 2u);
  EXPECT_FALSE(meta.HasMember("first"));
  EXPECT_STREQ(meta.MemberBegin()->name.GetString(), "use_camera");
  EXPECT_TRUE(meta["use_camera"].GetBool());
}

TEST_F(BadInputTest, DirectoryIsNamedAsADirectory) {
  ExpectRejected(dir_.str(), {dir_.str(), "is a directory"});
}

TEST_F(BadInputTest, DevZeroIsRefusedAtTheFirstByte) {
  ExpectRejected("/dev/zero", {"/dev/zero", "NUL byte at offset 0"});
}

TEST_F(BadInputTest, FileOverTheSizeLimitIsRefusedUnread) {
  const std::string path = golden_dir() + "/predictions/perfect.json";
  auto r = Score(path, 1000);
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find(path + ": results file is over the size limit of 1000 bytes"),
            std::string::npos)
      << r.status().message();
}

TEST_F(BadInputTest, SparseFileOverTheDefaultLimitIsRefused) {
  const std::string path = dir_.file("huge.json");
  write_text(path, "");
  std::filesystem::resize_file(path, kDefaultMaxResultsBytes + 1);  // sparse: no disk used
  ExpectRejected(path, {path, "over the size limit of 2147483648 bytes", "2147483649 bytes"});
}

TEST_F(BadInputTest, StreamWithoutKnownSizeStopsAtTheLimit) {
  // /proc files report size 0, so only the streaming bound can stop them.
  auto r = Score("/proc/self/status", 16);
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("over the size limit of 16 bytes"), std::string::npos)
      << r.status().message();
}

TEST_F(BadInputTest, EvalSetSamplesAreTheKeysTheScorerRequires) {
  auto tokens = eval_set_samples(golden_dir() + "/dataset", "v1.0-mini", "mini_val");
  ASSERT_TRUE(tokens.is_ok()) << tokens.status().message();
  EXPECT_EQ(tokens->size(), 18u);  // scene-0916 (10) + scene-0103 (8), spec §11
  std::set<std::string> keys;
  for (const auto& m : doc_["results"].GetObject()) keys.insert(m.name.GetString());
  EXPECT_EQ(std::set<std::string>(tokens->begin(), tokens->end()), keys);
  EXPECT_FALSE(eval_set_samples(golden_dir() + "/dataset", "v1.0-mini", "val").is_ok());  // version
}

TEST_F(BadInputTest, MissingTableNamesTheFile) {
  const std::string root = dir_.file("dataset");
  std::filesystem::copy(golden_dir() + "/dataset", root, std::filesystem::copy_options::recursive);
  std::filesystem::permissions(root + "/v1.0-mini", std::filesystem::perms::owner_all,
                               std::filesystem::perm_options::add);
  std::filesystem::remove(root + "/v1.0-mini/ego_pose.json");
  ExpectRejected(golden_dir() + "/predictions/perfect.json", {"ego_pose.json", "not found"}, root);
}

TEST_F(BadInputTest, NoBoxAtAllIsScoredAsZero) {
  for (auto& m : doc_["results"].GetObject()) m.value.Clear();
  EvalOptions opts;
  opts.results_path = Write("empty.json");
  opts.dataroot = golden_dir() + "/dataset";
  opts.version = "v1.0-mini";
  opts.eval_set = "mini_val";
  auto r = evaluate_detection(opts, nullptr);
  ASSERT_TRUE(r.is_ok()) << r.status().message();
  EXPECT_EQ(r->metrics.mean_ap, 0.0);
  EXPECT_EQ(r->metrics.nd_score, 0.0);
  EXPECT_EQ(r->metrics.tp_errors[kTrans], 1.0);
}

TEST_F(BadInputTest, CliExitsNonZeroAndNamesTheFile) {
  const std::string bin = std::string(FAULTLINE_BIN_DIR) + "/faultline";
  ASSERT_TRUE(std::filesystem::exists(bin)) << bin << " not built";
  std::string text = read_text(golden_dir() + "/predictions/perfect.json");
  text.resize(100);
  const std::string path = dir_.file("cli_bad.json");
  write_text(path, text);
  const std::string err = dir_.file("stderr.txt");
  const std::string cmd = bin + " score --results " + path + " --dataroot " + golden_dir() +
                          "/dataset --version v1.0-mini --eval_set mini_val --output_dir " +
                          dir_.file("o") + " > /dev/null 2> " + err;
  const int rc = std::system(cmd.c_str());
  EXPECT_NE(rc, 0);
  EXPECT_NE(read_text(err).find("cli_bad.json: malformed JSON at offset 100"), std::string::npos)
      << read_text(err);
}

TEST_F(BadInputTest, CliNamesADirectoryAndHonoursMaxResultsBytes) {
  const std::string bin = std::string(FAULTLINE_BIN_DIR) + "/faultline";
  ASSERT_TRUE(std::filesystem::exists(bin)) << bin << " not built";
  const std::string err = dir_.file("stderr.txt");
  auto score = [&](const std::string& results, const std::string& extra) {
    const std::string cmd = bin + " score --results " + results + " --dataroot " + golden_dir() +
                            "/dataset --version v1.0-mini --eval_set mini_val --output_dir " +
                            dir_.file("o") + " " + extra + " > /dev/null 2> " + err;
    return std::system(cmd.c_str());
  };
  EXPECT_NE(score(dir_.str(), ""), 0);
  EXPECT_NE(read_text(err).find(dir_.str() + ": is a directory"), std::string::npos)
      << read_text(err);
  EXPECT_NE(score(golden_dir() + "/predictions/perfect.json", "--max-results-bytes 1000"), 0);
  EXPECT_NE(read_text(err).find("over the size limit of 1000 bytes"), std::string::npos)
      << read_text(err);
  EXPECT_EQ(score(golden_dir() + "/predictions/perfect.json", "--quiet"), 0) << read_text(err);
}

}  // namespace
}  // namespace faultline::scoring
