// libFuzzer target: launch files (launch/launch_file.hpp) from arbitrary text. Bad input may only
// be refused with a ConfigError naming the file; an accepted launch file is taken through what
// `faultline launch` does next (a -p override, the sink's run identity, each node's parameters
// document and command line).
#include <sys/stat.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/config.hpp"
#include "fuzz_util.hpp"
#include "launch/launch_file.hpp"

namespace {

// A directory holding executable stand-ins for the nodes, so that bare exec names resolve without
// $PATH (the same for every process, left in place).
std::string fake_bin_dir() {
  const std::filesystem::path dir = faultline::fuzz::scratch_dir() / "faultline_fuzz_launch_bin";
  std::filesystem::create_directories(dir);
  for (const char* name :
       {"nusc_player", "fault_injector", "detector", "detection_sink", "v4l2_camera"}) {
    const auto path = dir / name;
    std::ofstream(path) << "#!/bin/sh\n";
    ::chmod(path.c_str(), 0755);
  }
  return dir.string();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace faultline;
  static const std::string bin_dir = fake_bin_dir();
  launch::LoadOptions options;
  options.bin_dir = bin_dir;
  options.search_path = false;
  options.env = [](const std::string& name) -> std::optional<std::string> {
    if (name == "FAULTLINE_RUN_DIR") return std::string("/tmp/run1");
    if (name == "EMPTY") return std::string();
    return std::nullopt;
  };
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    auto file = launch::parse_launch(text, "fuzz.yaml", options);
    try {
      launch::apply_override(file, file.nodes.front().name + ".rate:=2.0");
    } catch (const ConfigError&) {
    }
    launch::add_run_identity(file);
    for (const auto& node : file.nodes) {
      (void)launch::node_params_document(node);
      if (launch::node_command(node, "params.yaml").size() < 5)
        fuzz::fail("node command too short");
    }
  } catch (const ConfigError&) {
  }
  return 0;
}
