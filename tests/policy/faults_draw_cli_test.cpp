// `faultline faults draw --json` against the golden sets; bad arguments give a message and a
// non-zero exit.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <memory>
#include <string>

#include "rng/golden_json.hpp"

namespace faultline::policy {
namespace {

struct RunResult {
  int exit_code;
  std::string output;  // stdout and stderr
};

RunResult run_faultline(const std::string& args) {
  const std::string cmd = std::string(FAULTLINE_BIN_DIR) + "/faultline " + args + " 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
  std::string out;
  std::array<char, 4096> buf{};
  while (pipe && fgets(buf.data(), static_cast<int>(buf.size()), pipe.get())) out += buf.data();
  const int status = pclose(pipe.release());
  return {WEXITSTATUS(status), out};
}

TEST(FaultsDrawCliTest, CameraCrashJsonEqualsGoldenSet) {
  const auto doc = faultline::testing::load_golden_json("camera_crash.json");
  for (rapidjson::SizeType k = 0; k < 3; ++k) {  // three seeds keep the test quick
    const auto& s = doc["per_seed"][k];
    const unsigned seed = s["seed"].GetUint();
    for (int sev : {2, 5}) {
      const auto r =
          run_faultline("faults draw --type camera_crash --severity " + std::to_string(sev) +
                        " --seed " + std::to_string(seed) + " --json");
      ASSERT_EQ(r.exit_code, 0) << r.output;
      rapidjson::Document got;
      got.Parse(r.output.c_str());
      ASSERT_FALSE(got.HasParseError()) << r.output;
      const auto& expected = s["by_severity"][std::to_string(sev).c_str()]["dead_cameras"];
      ASSERT_TRUE(got["dead_cameras"].IsArray());
      ASSERT_EQ(got["dead_cameras"].Size(), expected.Size()) << r.output;
      for (rapidjson::SizeType i = 0; i < expected.Size(); ++i) {
        EXPECT_EQ(got["dead_cameras"][i].GetInt(), expected[i].GetInt());
      }
    }
  }
}

TEST(FaultsDrawCliTest, FrameLostJsonEqualsGoldenMasksWithLevel) {
  const auto doc = faultline::testing::load_golden_json("frame_lost.json");
  const auto& s = doc["per_seed"][0];
  // --level mid is severity 4.
  const auto r = run_faultline("faults draw --type frame_lost --level mid --seed " +
                               std::to_string(s["seed"].GetUint()) + " --frames 50 --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  rapidjson::Document got;
  got.Parse(r.output.c_str());
  ASSERT_FALSE(got.HasParseError()) << r.output;
  const auto& expected = s["by_severity"]["4"]["masks"];
  ASSERT_EQ(got["mask"].Size(), expected.Size());
  for (rapidjson::SizeType f = 0; f < expected.Size(); ++f) {
    std::string row;
    for (const auto& v : got["mask"][f].GetArray()) row += static_cast<char>('0' + v.GetInt());
    EXPECT_EQ(row, expected[f].GetString()) << "frame " << f;
  }
}

TEST(FaultsDrawCliTest, BadTypeAndSeverityAreNamedErrors) {
  auto r = run_faultline("faults draw --type camera_explode --severity 2 --seed 1 --json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("camera_explode"), std::string::npos) << r.output;
  r = run_faultline("faults draw --type frame_lost --severity 9 --seed 1 --json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("severity"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace faultline::policy
