#include "campaign/pipeline.hpp"

#include <filesystem>
#include <fstream>

#include "campaign/benchmark.hpp"
#include "common/config.hpp"
#include "launch/launch_file.hpp"

namespace faultline::campaign {
namespace fs = std::filesystem;

std::map<std::string, std::string> pipeline_variables(const BenchmarkOptions& o, const RunSpec& run,
                                                      const std::string& sockets,
                                                      const std::string& run_dir) {
  std::string detector = o.detector_cmd;
  if (detector.empty()) {
    detector = "detector";
    for (const auto& p : o.detector_params) detector += " " + p;
    for (const auto& p : run.variant_params) detector += " " + p;
  }
  return {{"FAULTLINE_SOCKETS", sockets},
          {"FAULTLINE_RUN_DIR", run_dir},
          {"DATAROOT", o.dataroot},
          {"VERSION", o.version},
          {"EVAL_SET", o.eval_set},
          {"SEED", std::to_string(run.seed)},
          {"CONDITION", run.corruption.empty() ? "clean" : run.corruption + "/" + run.level},
          {"DETECTOR", detector}};
}

namespace {

launch::LaunchFile load_pipeline(const BenchmarkOptions& o,
                                 const std::map<std::string, std::string>& vars) {
  launch::LoadOptions load;
  load.bin_dir = o.bin_dir;
  load.search_path = false;  // the nodes of this build, not whatever PATH holds
  if (!o.detector_cmd.empty())
    load.replaced_nodes.insert("detector");  // an external command runs instead
  // Only the run's variables: a benchmark must not change with the caller's environment.
  load.env = [&vars](const std::string& name) -> std::optional<std::string> {
    const auto it = vars.find(name);
    return it == vars.end() ? std::nullopt : std::optional<std::string>(it->second);
  };
  if (!o.pipeline_file.empty()) return launch::load_launch(o.pipeline_file, load);
  return launch::parse_launch(std::string(builtin_benchmark_pipeline()),
                              "launch/benchmark.yaml (built in)", load);
}

const launch::NodeSpec& find_node(const launch::LaunchFile& pipeline, const std::string& name) {
  for (const auto& n : pipeline.nodes) {
    if (n.name == name) return n;
  }
  throw ConfigError(pipeline.path + ": the benchmark needs a node named " + name);
}

// A YAML flow list of single-quoted strings ('' inside quotes stands for one ').
std::string quoted_list(const std::vector<std::string>& items) {
  std::string list = "[";
  for (std::size_t i = 0; i < items.size(); ++i) {
    list += i ? ", '" : "'";
    for (char c : items[i]) list += c == '\'' ? std::string("''") : std::string(1, c);
    list += "'";
  }
  return list + "]";
}

}  // namespace

RunPipeline run_pipeline(const BenchmarkOptions& o, const RunSpec& run, const std::string& sockets,
                         const std::string& run_dir) {
  launch::LaunchFile pipeline = load_pipeline(o, pipeline_variables(o, run, sockets, run_dir));
  for (const char* needed : {"detection_sink", "fault_injector", "detector", "nusc_player"}) {
    (void)find_node(pipeline, needed);
  }
  if (!run.corruption.empty()) {
    launch::apply_override(
        pipeline,
        "fault_injector.corruption:=" + injector_corruption_name(run.corruption) + "/" + run.level);
  }
  // Later overrides win: the variant's parameters over the detector's own.
  for (const auto& p : o.detector_params) launch::apply_override(pipeline, "detector." + p);
  for (const auto& p : run.variant_params) launch::apply_override(pipeline, "detector." + p);
  if (!o.scenes.empty())
    launch::apply_override(pipeline, "nusc_player.scenes:=" + quoted_list(o.scenes));

  const fs::path params_dir = fs::path(run_dir) / "params";
  std::error_code ec;
  fs::create_directories(params_dir, ec);
  if (ec) throw ConfigError(params_dir.string() + ": cannot create: " + ec.message());
  RunPipeline out;
  out.env = pipeline.env;
  auto& children = out.children;
  for (const auto& node : pipeline.nodes) {
    if (node.name == "detector" && !o.detector_cmd.empty()) {
      launch::ChildSpec c;
      c.name = "detector";
      c.required = false;
      c.argv = {"/bin/sh", "-c", o.detector_cmd};
      children.push_back(std::move(c));
      continue;
    }
    const std::string file = (params_dir / (node.name + ".yaml")).string();
    std::ofstream params(file);
    params << launch::node_params_yaml(node) << "\n";
    if (!params) throw ConfigError(file + ": cannot write the node's parameters");
    children.push_back(launch::child_spec(node, file));
  }
  return out;
}

}  // namespace faultline::campaign
