// Every golden case of golden/nusc_eval: all numbers of both metrics files within 1e-6 (NaN on both
// sides), cfg and meta exactly equal, filter counts equal to eval_log.txt, neg_* cases rejected
// with no metrics written.
#include <gtest/gtest.h>
#include <rapidjson/document.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <vector>

#include "scoring/evaluate.hpp"
#include "test_util.hpp"

namespace faultline::scoring {
namespace {

using testing::golden_dir;
using testing::read_text;
using testing::TempDir;

constexpr unsigned kFlags = rapidjson::kParseNanAndInfFlag | rapidjson::kParseFullPrecisionFlag;

rapidjson::Document parse(const std::string& path) {
  rapidjson::Document d;
  const std::string text = read_text(path);
  d.Parse<kFlags>(text.c_str(), text.size());
  EXPECT_FALSE(d.HasParseError()) << path;
  return d;
}

// Recursively compares; `tol` < 0 means exact (types and values).
void compare(const rapidjson::Value& mine, const rapidjson::Value& ref, const std::string& path,
             double tol, std::vector<std::string>& diffs) {
  if (diffs.size() > 10) return;
  if (ref.IsObject()) {
    if (!mine.IsObject()) {
      diffs.push_back(path + ": not an object");
      return;
    }
    std::vector<std::string> mk, rk;
    for (const auto& m : mine.GetObject()) mk.emplace_back(m.name.GetString());
    for (const auto& m : ref.GetObject()) rk.emplace_back(m.name.GetString());
    if (mk != rk)
      diffs.push_back(path + ": keys differ (count " + std::to_string(mk.size()) + " vs " +
                      std::to_string(rk.size()) + ")");
    for (const auto& m : ref.GetObject()) {
      const std::string key = m.name.GetString();
      if (key == "eval_time") continue;
      if (!mine.HasMember(m.name)) continue;
      const double sub_tol = (key == "cfg" || key == "meta") ? -1.0 : tol;
      compare(mine[m.name], m.value, path + "/" + key, sub_tol, diffs);
    }
  } else if (ref.IsArray()) {
    if (!mine.IsArray() || mine.Size() != ref.Size()) {
      diffs.push_back(path + ": array size differs");
      return;
    }
    for (rapidjson::SizeType i = 0; i < ref.Size(); ++i) {
      compare(mine[i], ref[i], path + "[" + std::to_string(i) + "]", tol, diffs);
    }
  } else if (ref.IsNumber()) {
    if (!mine.IsNumber()) {
      diffs.push_back(path + ": not a number");
      return;
    }
    const double a = mine.GetDouble(), b = ref.GetDouble();
    if (std::isnan(a) || std::isnan(b)) {
      if (std::isnan(a) != std::isnan(b)) diffs.push_back(path + ": NaN on one side only");
      return;
    }
    if (tol < 0) {
      if (a != b || mine.IsInt() != ref.IsInt()) diffs.push_back(path + ": not exactly equal");
    } else if (std::abs(a - b) > tol) {
      std::ostringstream os;
      os.precision(17);
      os << path << ": " << a << " vs devkit " << b;
      diffs.push_back(os.str());
    }
  } else if (mine != ref) {
    diffs.push_back(path + ": value differs");
  }
}

std::vector<std::size_t> log_counts(const std::string& log_text) {
  std::vector<std::size_t> counts;
  std::istringstream in(log_text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("=> ", 0) == 0) counts.push_back(std::stoul(line.substr(line.rfind(':') + 1)));
  }
  return counts;
}

std::vector<std::string> read_lines(const std::string& path) {
  std::vector<std::string> lines;
  std::istringstream in(read_text(path));
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The evaluation's progress lines, from "Initializing" to "Calculating metrics...", with the
// results path cut out of "Loaded results from <path>. Found ..." (the devkit ran with a relative
// path).
std::vector<std::string> eval_stages(const std::vector<std::string>& lines) {
  std::vector<std::string> stages;
  bool inside = false;
  for (const auto& line : lines) {
    inside = inside || line == "Initializing nuScenes detection evaluation";
    if (!inside) continue;
    const auto found = line.find(". Found detections for ");
    stages.push_back(line.rfind("Loaded results from ", 0) == 0 && found != std::string::npos
                         ? "Loaded results" + line.substr(found)
                         : line);
    if (line == "Calculating metrics...") break;
  }
  return stages;
}

// The 19 cases of predictions/cases.json, named here so that listing the tests reads no file; the
// set test below fails if cases.json and this list ever differ.
const std::vector<std::string>& case_names() {
  static const std::vector<std::string> names = {
      "perfect",           "noisy_low",          "noisy_high",
      "missing_classes",   "empty_samples",      "out_of_range",
      "yaw_wrap",          "zero_scores",        "duplicates",
      "attr_errors",       "velocity_nan",       "ties",
      "threshold_edges",   "grid_edge",          "low_recall",
      "custom_split",      "neg_too_many_boxes", "neg_bad_name",
      "neg_missing_sample"};
  return names;
}

class GoldenCaseTest : public ::testing::TestWithParam<std::string> {};

TEST_P(GoldenCaseTest, MatchesDevkit) {
  const std::string name = GetParam();
  const rapidjson::Document cases = parse(golden_dir() + "/predictions/cases.json");
  ASSERT_TRUE(cases.HasMember(name.c_str())) << "predictions/cases.json has no case " << name;
  const auto& c = cases[name.c_str()];
  TempDir out("golden_" + name);
  EvalOptions opts;
  opts.results_path = golden_dir() + "/predictions/" + c["file"].GetString();
  opts.dataroot = golden_dir() + "/dataset";
  opts.version = "v1.0-mini";
  opts.eval_set = c["eval_set"].GetString();
  opts.output_dir = out.str() + "/run";
  std::vector<std::string> progress;
  auto outcome =
      evaluate_detection(opts, [&progress](const std::string& line) { progress.push_back(line); });
  const std::string ref_dir = golden_dir() + "/results/" + name;
  if (!c["expect_error"].IsNull()) {
    ASSERT_FALSE(outcome.is_ok()) << name << " must be rejected";
    EXPECT_FALSE(std::filesystem::exists(opts.output_dir + "/metrics_summary.json"));
    EXPECT_FALSE(outcome.status().message().empty());
    return;
  }
  ASSERT_TRUE(outcome.is_ok()) << outcome.status().message();
  ASSERT_TRUE(write_eval_outputs(*outcome, opts.output_dir).is_ok());
  for (const char* file : {"metrics_summary.json", "metrics_details.json"}) {
    const auto mine = parse(opts.output_dir + "/" + file);
    const auto ref = parse(ref_dir + "/" + file);
    std::vector<std::string> diffs;
    compare(mine, ref, file, 1e-6, diffs);
    for (const auto& d : diffs) ADD_FAILURE() << name << ": " << d;
  }
  const auto expected = log_counts(read_text(ref_dir + "/eval_log.txt"));
  const auto& p = outcome->pred_counts;
  const auto& g = outcome->gt_counts;
  const std::vector<std::size_t> got = {p.original,        p.after_distance, p.after_points,
                                        p.after_bike_rack, g.original,       g.after_distance,
                                        g.after_points,    g.after_bike_rack};
  EXPECT_EQ(got, expected) << name << ": filter counts differ from eval_log.txt";
  EXPECT_EQ(eval_stages(progress), eval_stages(read_lines(ref_dir + "/eval_log.txt")))
      << name << ": progress lines differ from the devkit's eval_log.txt";
}

INSTANTIATE_TEST_SUITE_P(NuscEval, GoldenCaseTest, ::testing::ValuesIn(case_names()),
                         [](const ::testing::TestParamInfo<std::string>& param_info) {
                           std::string n;
                           bool up = true;
                           for (char ch : param_info.param) {
                             if (ch == '_') {
                               up = true;
                               continue;
                             }
                             n.push_back(up ? static_cast<char>(std::toupper(ch)) : ch);
                             up = false;
                           }
                           return n;
                         });

TEST(GoldenSetTest, HasSixteenAcceptedAndThreeRejectedCases) {
  const rapidjson::Document cases = parse(golden_dir() + "/predictions/cases.json");
  int accepted = 0, rejected = 0;
  for (const auto& m : cases.GetObject())
    (m.value["expect_error"].IsNull() ? accepted : rejected)++;
  EXPECT_EQ(accepted, 16);
  EXPECT_EQ(rejected, 3);
  std::vector<std::string> in_file;
  for (const auto& m : cases.GetObject()) in_file.emplace_back(m.name.GetString());
  EXPECT_EQ(in_file, case_names()) << "the test list and predictions/cases.json differ";
}

}  // namespace
}  // namespace faultline::scoring
