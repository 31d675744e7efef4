// `faultline dataset info`: scenes of a nuScenes dataroot with their sample and camera frame
// counts.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "dataset/nuscenes.hpp"

namespace faultline::cli {
namespace {

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "List the scenes of a nuScenes dataroot with sample and frame counts (one streaming pass "
      "over "
      "sample_data.json).",
      "faultline dataset info"};
  std::string dataroot, version = "v1.0-mini";
  app.add_option("--dataroot", dataroot, "folder holding <version>/, samples/, sweeps/")
      ->required();
  app.add_option("--version", version, "v1.0-mini, v1.0-trainval or v1.0-test");
  FAULTLINE_PARSE(app, argc, argv);

  auto reader = dataset::NuScenesReader::open(dataroot, version);
  if (!reader) return failure(reader.status().to_string());
  std::int64_t problems = 0;
  auto counts = reader->count_frames([&](const Status& s) {
    if (problems++ < 5) std::fprintf(stderr, "warning: %s\n", s.message().c_str());
  });
  if (!counts) return failure(counts.status().to_string());
  std::printf("%s/%s: %zu scenes\n", reader->dataroot().c_str(), version.c_str(),
              reader->scenes().size());
  std::printf("%-12s %8s %14s %10s %12s\n", "scene", "samples", "camera_frames", "cam_keys",
              "other_frames");
  std::int64_t samples = 0, cams = 0, keys = 0, others = 0;
  for (const auto& sc : reader->scenes()) {
    const auto& c = counts->at(sc.token);
    std::printf("%-12s %8d %14lld %10lld %12lld\n", sc.name.c_str(), sc.nbr_samples,
                static_cast<long long>(c.camera_frames),
                static_cast<long long>(c.camera_key_frames),
                static_cast<long long>(c.other_frames));
    samples += sc.nbr_samples;
    cams += c.camera_frames;
    keys += c.camera_key_frames;
    others += c.other_frames;
  }
  std::printf("%-12s %8lld %14lld %10lld %12lld\n", "total", static_cast<long long>(samples),
              static_cast<long long>(cams), static_cast<long long>(keys),
              static_cast<long long>(others));
  if (problems > 0)
    std::fprintf(stderr, "%lld bad sample_data records skipped\n",
                 static_cast<long long>(problems));
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(dataset_info, "dataset info",
                  "list scenes, samples and frame counts of a nuScenes dataroot", &run);
}  // namespace faultline::cli
