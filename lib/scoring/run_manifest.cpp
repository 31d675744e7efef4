// Manifest parsing (yaml-cpp reads both YAML and JSON) and NDS collection.
#include "scoring/run_manifest.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <map>

namespace faultline::scoring {

Result<std::vector<ConditionRun>> read_run_manifest(const std::string& path, std::string* detector,
                                                    double* latency_ms) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    return Status(StatusCode::kCorruptData, path + ": " + e.what());
  }
  if (!root.IsMap())
    return Status(StatusCode::kCorruptData,
                  path + ": expected a mapping of condition -> run folder");
  const std::filesystem::path base = std::filesystem::path(path).parent_path();
  YAML::Node runs = root["runs"] ? root["runs"] : root;
  std::vector<ConditionRun> out;
  try {
    if (root["detector"] && detector) *detector = root["detector"].as<std::string>();
    if (root["latency_ms"] && latency_ms) *latency_ms = root["latency_ms"].as<double>();
    if (root["fps"] && latency_ms) *latency_ms = 1000.0 / root["fps"].as<double>();
    for (const auto& kv : runs) {
      const auto key = kv.first.as<std::string>();
      if (key == "detector" || key == "latency_ms" || key == "fps" || key == "runs") continue;
      if (!kv.second.IsScalar()) {
        return Status(StatusCode::kCorruptData, path + ": " + key + ": expected a run folder path");
      }
      std::filesystem::path dir = kv.second.as<std::string>();
      if (dir.is_relative()) dir = base / dir;
      out.emplace_back(key, dir.string());
    }
  } catch (const YAML::Exception& e) {
    return Status(StatusCode::kCorruptData, path + ": " + e.what());
  }
  return out;
}

std::string condition_from_path(const std::string& dir) {
  std::filesystem::path p(dir);
  if (p.filename().empty()) p = p.parent_path();
  const std::string leaf = p.filename().string();
  if (severity_index(leaf) >= 0 && p.has_parent_path()) {
    return p.parent_path().filename().string() + "/" + leaf;
  }
  const auto cut = leaf.find_last_of("_-");
  if (cut != std::string::npos && severity_index(leaf.substr(cut + 1)) >= 0) {
    return leaf.substr(0, cut) + "/" + leaf.substr(cut + 1);
  }
  return leaf;
}

Result<DetectorScores> collect_detector_scores(const std::string& name,
                                               const std::vector<ConditionRun>& runs) {
  DetectorScores d;
  d.name = name;
  bool have_clean = false;
  std::vector<std::string> order;
  std::map<std::string, std::map<int, double>> levels;
  for (const auto& [condition, dir] : runs) {
    auto nds = read_nd_score(dir);
    if (!nds)
      return Status(nds.status().code(), "condition " + condition + ": " + nds.status().message());
    if (condition == "clean") {
      d.clean_nds = *nds;
      have_clean = true;
      continue;
    }
    const auto slash = condition.find('/');
    if (slash == std::string::npos) {
      return Status(StatusCode::kInvalidArgument,
                    "condition '" + condition + "' (" + dir +
                        "): expected 'clean' or '<corruption>/<easy|mid|hard>'");
    }
    const int level = severity_index(condition.substr(slash + 1));
    if (level < 0) {
      return Status(StatusCode::kInvalidArgument, "condition '" + condition + "': unknown level '" +
                                                      condition.substr(slash + 1) +
                                                      "' (easy, mid, hard)");
    }
    const std::string corruption = canonical_corruption(condition.substr(0, slash));
    if (!levels.count(corruption)) order.push_back(corruption);
    if (!levels[corruption].emplace(level, *nds).second) {
      return Status(StatusCode::kInvalidArgument, "condition '" + condition + "' given twice");
    }
  }
  if (!have_clean) return Status(StatusCode::kInvalidArgument, name + ": no 'clean' run given");
  for (const auto& c : order) {
    CorruptionScores cs{c, {}};
    int expect = 0;
    for (const auto& [lvl, nds] : levels[c]) {
      if (lvl != expect++) {
        return Status(StatusCode::kInvalidArgument,
                      name + ": corruption " + c + " lacks level " +
                          kSeverityLevels[static_cast<std::size_t>(expect - 1)]);
      }
      cs.nds_by_level.push_back(nds);
    }
    d.corruptions.push_back(cs);
  }
  return d;
}

}  // namespace faultline::scoring
