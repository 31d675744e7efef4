#include "export/merge.hpp"

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <map>

#include "dataset/nuscenes.hpp"
#include "export/manifest.hpp"

namespace faultline::exporter {
namespace {

namespace fs = std::filesystem;

constexpr const char* kMustAgree[] = {"version", "rng", "seed", "quality", "subsampling", "sweeps"};

bool same_root(const std::string& a, const std::string& b) {
  std::error_code ec1, ec2;
  return fs::weakly_canonical(a, ec1) == fs::weakly_canonical(b, ec2);
}

// Hard-links src to dst through a temporary name and rename(2), so dst is never missing or partial.
bool link_atomic(const std::string& src, const std::string& dst) {
  static std::atomic<unsigned> counter{0};
  const fs::path d(dst);
  const fs::path tmp =
      d.parent_path() / ("." + d.filename().string() + ".link-" + std::to_string(::getpid()) + "-" +
                         std::to_string(counter++));
  std::error_code ec;
  fs::create_hard_link(src, tmp, ec);
  if (ec) return false;
  fs::rename(tmp, d, ec);
  if (!ec) return true;
  std::error_code ignored;
  fs::remove(tmp, ignored);
  return false;
}

struct Group {
  Manifest merged;
  bool started = false;
  std::vector<std::string> sources;
  std::map<std::string, std::string> file_root;  // rel -> input root holding the file
};

}  // namespace

Result<MergeSummary> merge_exports(const std::vector<std::string>& inputs, const std::string& out,
                                   const std::string& tool_version, bool hard_link) {
  if (inputs.empty()) return Status(StatusCode::kInvalidArgument, "merge: no input folders");
  std::map<std::string, Group> groups;  // "<Condition>/<level>"
  for (const auto& root : inputs) {
    std::error_code ec;
    if (!fs::is_directory(root, ec))
      return Status(StatusCode::kNotFound, "merge: not a folder: " + root);
    for (const auto& cond : fs::directory_iterator(root, ec)) {
      if (!cond.is_directory()) continue;
      for (const auto& lvl : fs::directory_iterator(cond.path(), ec)) {
        if (!lvl.is_directory()) continue;
        for (const auto& file : fs::directory_iterator(lvl.path(), ec)) {
          const std::string name = file.path().filename().string();
          if (name.rfind("manifest", 0) != 0 || file.path().extension() != ".json") continue;
          auto m = read_manifest(file.path().string());
          if (!m) return m.status();
          const std::string key =
              cond.path().filename().string() + "/" + lvl.path().filename().string();
          Group& g = groups[key];
          if (!g.started) {
            g.merged = *m;
            g.merged.files.clear();
            g.merged.errors.clear();
            g.merged.tool_version = tool_version;
            g.started = true;
          } else {
            for (const char* k : kMustAgree) {
              if (g.merged.config[k] != m->config[k]) {
                return Status(StatusCode::kInvalidArgument,
                              "merge: " + file.path().string() + ": config " + k + " = '" +
                                  m->config[k] + "' but an earlier shard has '" +
                                  g.merged.config[k] + "'");
              }
            }
          }
          g.sources.push_back(file.path().string());
          for (const auto& [rel, e] : m->files) {
            auto it = g.merged.files.find(rel);
            if (it != g.merged.files.end() && it->second.crc32 != e.crc32) {
              return Status(StatusCode::kCorruptData,
                            "merge: " + key + "/" + rel + " has different checksums in two shards");
            }
            g.merged.files[rel] = e;
            g.file_root[rel] = root;
          }
          for (const auto& [rel, e] : m->errors) g.merged.errors[rel] = e;
        }
      }
    }
  }
  MergeSummary summary;
  for (auto& [key, g] : groups) {
    Manifest& m = g.merged;
    for (const auto& [rel, e] : m.files)
      m.errors.erase(rel);  // another shard or a later run made it
    const std::string out_dir = out + "/" + key;
    std::vector<std::string> copy_failed;
    for (const auto& [rel, e] : m.files) {
      const std::string& root = g.file_root[rel];
      if (same_root(root, out)) continue;
      const std::string src = root + "/" + key + "/" + rel;
      const std::string dst = out_dir + "/" + rel;
      auto bytes = dataset::read_file(src);
      Status s = bytes ? Status::ok() : bytes.status();
      if (s &&
          (bytes->size() != e.size_bytes || crc32_of(bytes->data(), bytes->size()) != e.crc32)) {
        s = Status(StatusCode::kCorruptData, "checksum mismatch in " + src);
      }
      if (s) {
        std::error_code ec;
        fs::create_directories(fs::path(dst).parent_path(), ec);
        if (!hard_link || !link_atomic(src, dst))
          s = write_file_atomic(dst, bytes->data(), bytes->size());
      }
      if (s) {
        ++summary.copied;
      } else {
        m.errors[rel] = InputError{src, s.to_string()};
        copy_failed.push_back(rel);
      }
    }
    for (const auto& rel : copy_failed) m.files.erase(rel);
    m.config["shard"] = "merged";
    std::string from;
    for (const auto& s : g.sources) from += (from.empty() ? "" : ",") + s;
    m.config["merged_from"] = from;
    m.written = static_cast<std::int64_t>(m.files.size());
    m.skipped = 0;
    m.expected = static_cast<std::int64_t>(m.files.size() + m.errors.size());
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    if (Status s = write_manifest_atomic(out_dir + "/manifest.json", m); !s) return s;
    ++summary.folders;
    summary.files += static_cast<std::int64_t>(m.files.size());
    summary.failed += static_cast<std::int64_t>(m.errors.size());
    for (const auto& [rel, e] : m.errors)
      summary.problems.push_back(key + "/" + rel + ": " + e.error);
  }
  return summary;
}

}  // namespace faultline::exporter
