// `faultline dataset synth`: writes a synthetic dataset in the exact nuScenes layout (tables +
// rendered JPEGs).
#include <CLI/CLI.hpp>
#include <cstdio>

#include "cli/command.hpp"
#include "cli/parse.hpp"
#include "dataset/synth.hpp"

namespace faultline::cli {
namespace {

ExitStatus run(int argc, char** argv) {
  CLI::App app{
      "Write a small synthetic dataset in the exact nuScenes format: all tables the camera replay "
      "and the "
      "official detection evaluation need, plus 1600x900 JPEGs rendered from the same 3D scene.",
      "faultline dataset synth"};
  dataset::SynthOptions opt;
  app.add_option("--out", opt.out_dir, "dataroot to create")->required();
  app.add_option("--scenes", opt.scenes,
                 "number of scenes (the first 10 use the devkit's mini split names)")
      ->check(CLI::Range(1, 9999));
  app.add_option("--seconds", opt.seconds, "seconds per scene (2 Hz key frames)")
      ->check(CLI::Range(0.5, 600.0));
  app.add_option("--seed", opt.seed, "random seed; the same seed gives byte-identical files");
  app.add_option("--version", opt.version,
                 "table folder name (v1.0-mini, v1.0-trainval, v1.0-test)");
  app.add_flag("--metadata-only", opt.metadata_only, "write the tables only, no images");
  app.add_option("--width", opt.image_width, "image width in px (intrinsics scale with it)");
  app.add_option("--height", opt.image_height, "image height in px");
  app.add_option("--quality", opt.jpeg_quality, "JPEG quality")->check(CLI::Range(1, 100));
  app.add_option("--sensor-noise", opt.sensor_noise,
                 "per-pixel sensor noise in 8-bit levels (0 = flat render; the default gives JPEGs "
                 "of nuScenes' size)")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  app.add_option("--threads", opt.threads, "render/encode threads")->check(CLI::Range(1, 64));
  bool no_annotations = false;
  app.add_flag("--no-annotations", no_annotations,
               "write empty sample_annotation/instance tables (like v1.0-test)");
  FAULTLINE_PARSE(app, argc, argv);
  opt.annotations = !no_annotations;

  auto result = dataset::write_synthetic_dataset(
      opt, [](const std::string& stage, std::int64_t done, std::int64_t total) {
        std::fprintf(stderr, "\r%s %lld/%lld", stage.c_str(), static_cast<long long>(done),
                     static_cast<long long>(total));
        std::fflush(stderr);
      });
  std::fprintf(stderr, "\n");
  if (!result) return failure(result.status().to_string());
  const auto& s = *result;
  std::printf(
      "wrote %s/%s: %d scenes, %d samples, %lld sample_data (%lld camera), %lld images, %lld "
      "annotations, "
      "%lld instances, %.1f MB in %.2f s\n",
      opt.out_dir.c_str(), opt.version.c_str(), s.scenes, s.samples,
      static_cast<long long>(s.sample_data), static_cast<long long>(s.camera_frames),
      static_cast<long long>(s.images_written), static_cast<long long>(s.annotations),
      static_cast<long long>(s.instances), static_cast<double>(s.bytes_written) / 1e6,
      s.wall_seconds);
  return 0;
}

}  // namespace
FAULTLINE_COMMAND(dataset_synth, "dataset synth", "write a synthetic nuScenes-format dataset",
                  &run);
}  // namespace faultline::cli
