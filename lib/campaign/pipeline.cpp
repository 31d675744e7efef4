#include "campaign/pipeline.hpp"

#include <filesystem>
#include <fstream>

#include "campaign/benchmark.hpp"
#include "campaign/soak.hpp"
#include "campaign/soak_report.hpp"
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

std::map<std::string, std::string> soak_variables(const SoakOptions& o,
                                                  const std::string& sockets) {
  return {{"FAULTLINE_SOCKETS", sockets},
          {"DATAROOT", o.dataroot},
          {"VERSION", o.version},
          {"RATE", soak_detail::fmt(o.rate, 3)},
          {"SEED", std::to_string(o.seed)}};
}

namespace {

// Which pipeline a campaign runs and what it needs of it.
struct PipelineChoice {
  const char* campaign;             // "benchmark", "soak": names it in errors
  std::string file;                 // the user's --pipeline; "" = the built-in one
  std::string_view builtin;         // launch/<campaign>.yaml compiled in
  std::string bin_dir;              // node executables
  std::string detector_cmd;         // external detector replacing the `detector` node; "" = none
  std::vector<std::string> needed;  // nodes the campaign talks to or overrides
};

launch::LaunchFile load_pipeline(const PipelineChoice& c,
                                 const std::map<std::string, std::string>& vars) {
  launch::LoadOptions load;
  load.bin_dir = c.bin_dir;
  load.search_path = false;  // the nodes of this build, not whatever PATH holds
  if (!c.detector_cmd.empty())
    load.replaced_nodes.insert("detector");  // an external command runs instead
  // Only the run's variables: a campaign must not change with the caller's environment.
  load.env = [&vars](const std::string& name) -> std::optional<std::string> {
    const auto it = vars.find(name);
    return it == vars.end() ? std::nullopt : std::optional<std::string>(it->second);
  };
  launch::LaunchFile pipeline =
      c.file.empty()
          ? launch::parse_launch(std::string(c.builtin),
                                 "launch/" + std::string(c.campaign) + ".yaml (built in)", load)
          : launch::load_launch(c.file, load);
  for (const auto& needed : c.needed) {
    bool found = false;
    for (const auto& n : pipeline.nodes) found = found || n.name == needed;
    if (!found) {
      throw ConfigError(pipeline.path + ": the " + c.campaign + " needs a node named " + needed);
    }
  }
  return pipeline;
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

// Writes each node's parameters to <dir>/params/<node>.yaml and returns the children; the
// `detector` node runs `detector_cmd` under sh -c instead when one is given (required as the
// node says).
RunPipeline write_children(const launch::LaunchFile& pipeline, const std::string& dir,
                           const std::string& detector_cmd) {
  const fs::path params_dir = fs::path(dir) / "params";
  std::error_code ec;
  fs::create_directories(params_dir, ec);
  if (ec) throw ConfigError(params_dir.string() + ": cannot create: " + ec.message());
  RunPipeline out;
  out.env = pipeline.env;
  for (const auto& node : pipeline.nodes) {
    if (node.name == "detector" && !detector_cmd.empty()) {
      launch::ChildSpec c;
      c.name = "detector";
      c.required = node.required;
      c.argv = {"/bin/sh", "-c", detector_cmd};
      out.children.push_back(std::move(c));
      continue;
    }
    const std::string file = (params_dir / (node.name + ".yaml")).string();
    std::ofstream params(file);
    params << launch::node_params_yaml(node) << "\n";
    if (!params) throw ConfigError(file + ": cannot write the node's parameters");
    out.children.push_back(launch::child_spec(node, file));
  }
  return out;
}

}  // namespace

RunPipeline run_pipeline(const BenchmarkOptions& o, const RunSpec& run, const std::string& sockets,
                         const std::string& run_dir) {
  const PipelineChoice choice{"benchmark",
                              o.pipeline_file,
                              builtin_benchmark_pipeline(),
                              o.bin_dir,
                              o.detector_cmd,
                              {"detection_sink", "fault_injector", "detector", "nusc_player"}};
  launch::LaunchFile pipeline = load_pipeline(choice, pipeline_variables(o, run, sockets, run_dir));
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
  return write_children(pipeline, run_dir, o.detector_cmd);
}

RunPipeline soak_pipeline(const SoakOptions& o, const std::string& sockets) {
  const PipelineChoice choice{
      "soak",    o.pipeline_file, builtin_soak_pipeline(),
      o.bin_dir, o.detector_cmd,  {"fault_injector", "detector", "nusc_player"}};
  launch::LaunchFile pipeline = load_pipeline(choice, soak_variables(o, sockets));
  if (!o.corruption.empty())
    launch::apply_override(pipeline, "fault_injector.corruption:=" + o.corruption);
  if (o.detector_cmd.empty()) {
    for (const auto& p : o.detector_params) launch::apply_override(pipeline, "detector." + p);
  }
  if (!o.scenes.empty())
    launch::apply_override(pipeline, "nusc_player.scenes:=" + quoted_list(o.scenes));
  RunPipeline out = write_children(pipeline, o.out_dir, o.detector_cmd);
  for (auto& c : out.children) {
    // In a soak every node must survive: each is required, so an exit ends the run and is
    // reported.
    c.required = true;
    // The --faults file goes first: the pipeline's parameters, given after it, win over it.
    if (c.name == "fault_injector" && !o.injector_params_file.empty())
      c.argv.insert(c.argv.begin() + 3, {"--params", o.injector_params_file});
  }
  return out;
}

}  // namespace faultline::campaign
