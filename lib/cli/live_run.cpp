#include "cli/live_run.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "dataset/synth.hpp"

namespace faultline::cli {
namespace fs = std::filesystem;

std::string executable_dir() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) return ".";
  buf[n] = 0;
  return fs::path(buf).parent_path().string();
}

Status ensure_synth_dataset(const std::string& dir) {
  if (fs::exists(fs::path(dir) / "v1.0-mini" / "sample.json")) return Status::ok();
  std::fprintf(stderr, "generating the embedded synthetic dataset into %s ...\n", dir.c_str());
  dataset::SynthOptions so;
  so.out_dir = dir;
  auto s = dataset::write_synthetic_dataset(so);
  return s ? Status::ok() : s.status();
}

}  // namespace faultline::cli
