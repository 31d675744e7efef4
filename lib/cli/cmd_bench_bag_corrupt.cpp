// `faultline bench bag-corrupt`: arguments of the bag corrupt vs export measurement
// (bench/lib/bench/bag_corrupt.hpp).
#include <CLI/CLI.hpp>

#include "bench/bag_corrupt.hpp"
#include "cli/command.hpp"
#include "cli/parse.hpp"

namespace faultline::cli {
namespace {

int run(int argc, char** argv) {
  CLI::App app{
      "bag corrupt frames/s on 1 and 2 threads against export on the same frames (the key-frame "
      "camera JPEGs of a "
      "synthetic nuScenes dataset, also written as a rosbag2 bag of CompressedImage topics). Runs "
      "alternate tool "
      "and thread count; medians over --reps.",
      argv[0]};
  bench::BagCorruptBenchOptions o;
  app.add_option("--reps", o.reps, "runs per (tool, threads)")->capture_default_str();
  app.add_option("--scenes", o.scenes, "synthetic scenes")->capture_default_str();
  app.add_option("--seconds", o.seconds, "seconds per scene (key frames at 2 Hz, 6 cameras)")
      ->capture_default_str();
  app.add_option("--width", o.width, "image width")->capture_default_str();
  app.add_option("--height", o.height, "image height")->capture_default_str();
  app.add_option("--fault", o.fault, "image corruption")->capture_default_str();
  app.add_option("--level", o.level, "easy, mid or hard")->capture_default_str();
  app.add_option("--rng", o.rng, "numpy or fast")->capture_default_str();
  app.add_option("--dir", o.work_dir,
                 "scratch directory (default: a fresh one under the temp dir, removed)");
  FAULTLINE_PARSE(app, argc, argv);
  return bench::run_bag_corrupt_bench(o);
}

}  // namespace
FAULTLINE_COMMAND(bench_bag_corrupt, "bench bag-corrupt",
                  "bag corrupt frames/s on 1 and 2 threads vs export", &run);
}  // namespace faultline::cli
