// `faultline corrupt` end to end: golden reproduction through files, --level and --angle, and clear
// errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "corruption/corrupt.hpp"
#include "corruption/golden_cases.hpp"
#include "rng/golden_json.hpp"
#include "test_data.hpp"

namespace faultline::testing {
namespace {

struct RunResult {
  int exit_code;
  std::string output;
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

std::string temp_png(const std::string& stem) {
  return ::testing::TempDir() + "/faultline_" + stem + "_" + std::to_string(::getpid()) + ".png";
}

const GoldenCase& find_case(const std::vector<GoldenCase>& cases, const std::string& name) {
  for (const auto& c : cases) {
    if (c.name == name) return c;
  }
  throw std::runtime_error("no golden case " + name);
}

TEST(CorruptCliTest, NumpyModeReproducesGoldenFilesBitExactly) {
  const auto cases = load_golden_cases();
  for (const std::string name : {"snow_chart_333x197_sev2", "dark_chart_333x197_sev3",
                                 "fog_chart_333x197_sev4", "brightness_chart_333x197_sev5"}) {
    const GoldenCase& c = find_case(cases, name);
    const std::string out = temp_png(name);
    const auto r =
        run_faultline("corrupt --type " + std::string(corruption::to_string(c.type)) +
                      " --severity " + std::to_string(c.severity) + " --seed " +
                      std::to_string(c.seed.value_or(0)) + " --rng numpy --in " +
                      test_data::fixture(golden_dir() + "/" + c.input_file) + " --out " + out);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(compare_with_reference(cv::imread(out, cv::IMREAD_COLOR), c), "");
    std::remove(out.c_str());
  }
}

TEST(CorruptCliTest, AngleInjectionAndLevelGiveTheGoldenMotionBlur) {
  const auto cases = load_golden_cases();
  const GoldenCase& c = find_case(cases, "motion_blur_chart_333x197_sev4");  // sev 4 = level mid
  char angle[64];
  std::snprintf(angle, sizeof angle, "%.17g", *c.angle_deg);
  const std::string out = temp_png("mb");
  const auto r =
      run_faultline("corrupt --type motion_blur --level mid --angle " + std::string(angle) +
                    " --rng fast --seed 999 --in " +
                    test_data::fixture(golden_dir() + "/" + c.input_file) + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(compare_with_reference(cv::imread(out, cv::IMREAD_COLOR), c), "");
  std::remove(out.c_str());
}

TEST(CorruptCliTest, BadTypeSeverityAndFilesAreNamedErrors) {
  const std::string in = test_data::fixture(golden_dir() + "/inputs/chart_333x197.png");
  const std::string out = temp_png("err");
  auto r = run_faultline("corrupt --type rain --severity 2 --in " + in + " --out " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("rain"), std::string::npos) << r.output;
  // A stream fault is a known name, but one image gives it nothing to act on.
  for (const char* type : {"stale_frames", "timestamp_skew", "camera_crash"}) {
    r = run_faultline("corrupt --type " + std::string(type) + " --in " + in + " --out " + out);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.output.find("--type " + std::string(type) + " is a stream fault"),
              std::string::npos)
        << r.output;
  }
  r = run_faultline("corrupt --type fog --severity 7 --in " + in + " --out " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("severity"), std::string::npos) << r.output;
  r = run_faultline("corrupt --type fog --level extreme --in " + in + " --out " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("extreme"), std::string::npos) << r.output;
  r = run_faultline("corrupt --type fog --severity 2 --in /nonexistent/frame.png --out " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("/nonexistent/frame.png"), std::string::npos) << r.output;
  r = run_faultline("corrupt --type fog --severity 2 --rng mersenne --in " + in + " --out " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("mersenne"), std::string::npos) << r.output;
}

// The imagecorruptions types by name through files, in numpy mode the reference's output
// (ext/<type>.json);
// --frost-dir swaps frost's textures; a directory without textures is a named error.
TEST(CorruptCliTest, ImagecorruptionsTypesAndFrostTextures) {
  const std::string in = test_data::fixture(golden_dir() + "/inputs/chart_333x197.png");
  const std::string out = temp_png("ext");
  const auto frost = load_golden_json("ext/frost.json");
  const auto& rec = frost["outputs"][0];  // chart_333x197, severity 1
  ASSERT_STREQ(rec["input"].GetString(), "chart_333x197");
  auto r = run_faultline(
      "corrupt --type frost --severity " + std::to_string(rec["severity"].GetInt()) + " --seed " +
      std::to_string(rec["seed"].GetUint()) + " --rng numpy --in " + in + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(pixel_sha256(cv::imread(out, cv::IMREAD_COLOR)), rec["sha256_bgr_pixels"].GetString());
  // One flat grey texture: the output is clip(a * image + b * 128) everywhere.
  const std::string dir = ::testing::TempDir() + "/faultline_frost_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  cv::imwrite(dir + "/grey.png", cv::Mat(400, 500, CV_8UC3, cv::Scalar::all(128)));
  r = run_faultline("corrupt --type frost --severity 1 --frost-dir " + dir + " --in " + in +
                    " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat image = cv::imread(in, cv::IMREAD_COLOR), got = cv::imread(out, cv::IMREAD_COLOR);
  cv::Mat expected;
  image.convertTo(expected, CV_64FC3, 1.0, 0.4 * 128);
  cv::min(expected, 255.0, expected);
  expected.convertTo(expected, CV_8UC3, 1.0, -0.4999);  // truncation
  EXPECT_LE(cv::norm(got, expected, cv::NORM_INF), 0.0);
  std::filesystem::remove(dir + "/grey.png");
  r = run_faultline("corrupt --type frost --severity 1 --frost-dir " + dir + " --in " + in +
                    " --out " + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--frost-dir"), std::string::npos) << r.output;
  std::filesystem::remove_all(dir);
  for (const char* type :
       {"defocus_blur", "glass_blur", "zoom_blur", "elastic_transform", "spatter"}) {
    r = run_faultline(std::string("corrupt --type ") + type + " --level mid --in " + in +
                      " --out " + out);
    EXPECT_EQ(r.exit_code, 0) << type << ": " << r.output;
  }
  r = run_faultline("corrupt --type rain --severity 2 --in " + in + " --out " + out);
  EXPECT_NE(r.output.find("elastic_transform"), std::string::npos) << r.output;
  std::remove(out.c_str());
}

// Faultline's sensor faults by name: the CLI's frame is the library's fast-mode frame for the seed
// (one model at time 0); the help lists them.
TEST(CorruptCliTest, SensorFaultsByName) {
  const std::string in = test_data::fixture(golden_dir() + "/inputs/chart_333x197.png");
  const std::string out = temp_png("sensor");
  const cv::Mat image = cv::imread(in, cv::IMREAD_COLOR);
  for (const char* type : {"soiling", "water_drops", "glare", "exposure_flicker"}) {
    auto r = run_faultline(std::string("corrupt --type ") + type + " --severity 4 --seed 9 --in " +
                           in + " --out " + out);
    ASSERT_EQ(r.exit_code, 0) << type << ": " << r.output;
    rng::FastRng rng(9);
    auto expected = corruption::corrupt(image, *corruption::corruption_from_string(type), 4, rng);
    ASSERT_TRUE(expected);
    EXPECT_EQ(cv::norm(cv::imread(out, cv::IMREAD_COLOR), *expected, cv::NORM_INF), 0.0) << type;
    EXPECT_GT(cv::norm(*expected, image, cv::NORM_INF), 0.0) << type;
  }
  const auto help = run_faultline("corrupt --help");
  EXPECT_NE(help.output.find("water_drops"), std::string::npos) << help.output;
  EXPECT_NE(help.output.find("exposure_flicker"), std::string::npos) << help.output;
  std::remove(out.c_str());
}

// #22: the input is read with a limit (kMaxImageFileBytes, 1 GiB); one byte over is refused unread
// (a sparse file), and /dev/zero stops at the limit.
TEST(CorruptCliTest, AnInputOneByteOverTheImageLimitIsRefusedNamingIt) {
  const std::string in =
      ::testing::TempDir() + "/faultline_big_" + std::to_string(::getpid()) + ".png";
  std::ofstream(in).close();
  std::filesystem::resize_file(in, (std::uint64_t{1} << 30) + 1);  // sparse: no disk used
  auto r =
      run_faultline("corrupt --type fog --severity 2 --in " + in + " --out " + temp_png("big"));
  std::filesystem::remove(in);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("input image " + in + ": larger than the limit of 1 GiB"),
            std::string::npos)
      << r.output;
}

TEST(CorruptCliTest, NonFiniteAngleIsAnErrorNamingTheOption) {
  const std::string in = test_data::fixture(golden_dir() + "/inputs/chart_333x197.png");
  const std::string out = temp_png("angle");
  for (const char* angle : {"nan", "inf", "-inf"}) {
    const auto r = run_faultline("corrupt --type motion_blur --severity 3 --angle " +
                                 std::string(angle) + " --in " + in + " --out " + out);
    EXPECT_EQ(r.exit_code, 2) << angle << ": " << r.output;
    EXPECT_NE(r.output.find("--angle must be a finite number"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(out));
}

// A JPEG cut in half: refused with the reason and the file (OpenCV alone renders it half grey and
// exits 0);
// --allow-partial corrupts the partial decode and says so.
TEST(CorruptCliTest, TruncatedJpegIsRefusedUnlessPartialIsAllowed) {
  std::vector<std::uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", read_golden_png("inputs/night_street.png"), jpeg));
  const std::string in =
      ::testing::TempDir() + "/faultline_truncated_" + std::to_string(::getpid()) + ".jpg";
  {
    std::ofstream f(in, std::ios::binary);
    f.write(reinterpret_cast<const char*>(jpeg.data()),
            static_cast<std::streamsize>(jpeg.size() / 2));
  }
  const std::string out = temp_png("truncated");
  auto r = run_faultline("corrupt --type fog --severity 2 --in " + in + " --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("truncated"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(in), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
  r = run_faultline("corrupt --type fog --severity 2 --allow-partial --in " + in + " --out " + out);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning"), std::string::npos) << r.output;
  EXPECT_EQ(cv::imread(out, cv::IMREAD_COLOR).size(), cv::Size(640, 360));
  std::remove(out.c_str());
  std::remove(in.c_str());
}

// --gallery: one strip per --types entry with progress on stderr, on the input frame or the
// built-in one; bad entries, paths and mixed modes are named errors.
TEST(CorruptCliTest, GalleryWritesStripsAndIndexAndNamesItsErrors) {
  const std::string dir =
      ::testing::TempDir() + "/faultline_gallery_cli_" + std::to_string(::getpid());
  std::filesystem::remove_all(dir);
  const std::string in = test_data::fixture(golden_dir() + "/inputs/chart_333x197.png");
  auto r = run_faultline("corrupt --gallery " + dir + " --types fog,brightness --thumb-width 48 " +
                         "--seed 3 --in " + in);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("[1/2] fog"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("[2/2] brightness"), std::string::npos) << r.output;
  for (const char* f : {"fog.jpg", "brightness.jpg"}) {
    // 48 px tiles of a 333 x 197 frame: 28 px high; six of them 2 px apart.
    EXPECT_EQ(cv::imread(dir + "/" + f, cv::IMREAD_COLOR).size(), cv::Size(6 * 48 + 10, 28)) << f;
  }
  std::ifstream index(dir + "/index.md");
  const std::string md((std::istreambuf_iterator<char>(index)), std::istreambuf_iterator<char>());
  EXPECT_NE(md.find("`chart_333x197.png`"), std::string::npos) << md;
  EXPECT_NE(md.find("--types fog,brightness"), std::string::npos) << md;
  r = run_faultline("corrupt --gallery " + dir + " --types fog,rain");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("unknown --types entry 'rain'"), std::string::npos) << r.output;
  r = run_faultline("corrupt --gallery " + dir + " --in /nonexistent/frame.png");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/frame.png"), std::string::npos) << r.output;
  r = run_faultline("corrupt --gallery " + dir + " --type fog --severity 2");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--type"), std::string::npos) << r.output;
  r = run_faultline("corrupt --severity 2 --in " + in + " --out " + dir + "/x.png");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--type is required"), std::string::npos) << r.output;
  r = run_faultline("corrupt --help");
  EXPECT_NE(r.output.find("--gallery"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--thumb-width"), std::string::npos) << r.output;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace faultline::testing
