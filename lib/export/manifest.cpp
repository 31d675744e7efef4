#include "export/manifest.hpp"

#include <rapidjson/document.h>
#include <rapidjson/prettywriter.h>
#include <rapidjson/stringbuffer.h>
#include <unistd.h>
#include <zlib.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace faultline::exporter {

std::uint32_t crc32_of(const std::uint8_t* data, std::size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  while (size > 0) {  // zlib takes uInt lengths
    const uInt chunk = size > (1u << 30) ? (1u << 30) : static_cast<uInt>(size);
    crc = crc32(crc, data, chunk);
    data += chunk;
    size -= chunk;
  }
  return static_cast<std::uint32_t>(crc);
}

std::string manifest_json(const Manifest& m) {
  rapidjson::StringBuffer buf;
  rapidjson::PrettyWriter<rapidjson::StringBuffer> w(buf);
  w.SetIndent(' ', 1);
  w.StartObject();
  w.Key("tool_version");
  w.String(m.tool_version.c_str());
  w.Key("condition");
  w.String(m.condition.c_str());
  w.Key("level");
  w.String(m.level.c_str());
  w.Key("severity");
  w.Int(m.severity);
  w.Key("config");
  w.StartObject();
  for (const auto& [k, v] : m.config) {
    w.Key(k.c_str());
    w.String(v.c_str());
  }
  w.EndObject();
  w.Key("seed_derivation");
  w.String(m.seed_derivation.c_str());
  if (!m.dead_cameras.empty() || m.condition == "CameraCrash") {
    w.Key("dead_cameras");
    w.StartArray();
    for (int c : m.dead_cameras) w.Int(c);
    w.EndArray();
  }
  w.Key("counts");
  w.StartObject();
  w.Key("expected");
  w.Int64(m.expected);
  w.Key("files");
  w.Int64(static_cast<std::int64_t>(m.files.size()));
  w.Key("written");
  w.Int64(m.written);
  w.Key("skipped");
  w.Int64(m.skipped);
  w.Key("failed");
  w.Int64(static_cast<std::int64_t>(m.errors.size()));
  w.EndObject();
  w.Key("errors");
  w.StartArray();
  for (const auto& [k, e] : m.errors) {
    w.StartObject();
    w.Key("file");
    w.String(k.c_str());
    w.Key("input");
    w.String(e.input.c_str());
    w.Key("error");
    w.String(e.error.c_str());
    w.EndObject();
  }
  w.EndArray();
  w.Key("files");
  w.StartObject();
  char hex[16];
  for (const auto& [k, f] : m.files) {
    w.Key(k.c_str());
    w.StartObject();
    std::snprintf(hex, sizeof hex, "%08x", f.crc32);
    w.Key("crc32");
    w.String(hex);
    w.Key("size");
    w.Uint64(f.size_bytes);
    w.Key("seed");
    w.Uint64(f.seed);
    w.Key("kind");
    w.String(f.kind.c_str());
    w.EndObject();
  }
  w.EndObject();
  w.EndObject();
  return std::string(buf.GetString(), buf.GetSize()) + "\n";
}

Result<Manifest> parse_manifest(const std::string& json, const std::string& origin) {
  rapidjson::Document d;
  d.Parse(json.c_str(), json.size());
  auto bad = [&](const std::string& what) {
    return Status(StatusCode::kCorruptData, origin + ": " + what);
  };
  if (d.HasParseError() || !d.IsObject()) return bad("not a JSON object");
  Manifest m;
  auto str = [&](const char* key, std::string& out) {
    if (d.HasMember(key) && d[key].IsString()) out = d[key].GetString();
  };
  str("tool_version", m.tool_version);
  str("condition", m.condition);
  str("level", m.level);
  str("seed_derivation", m.seed_derivation);
  if (d.HasMember("severity") && d["severity"].IsInt()) m.severity = d["severity"].GetInt();
  if (d.HasMember("config") && d["config"].IsObject()) {
    for (const auto& kv : d["config"].GetObject()) {
      if (kv.value.IsString()) m.config[kv.name.GetString()] = kv.value.GetString();
    }
  }
  if (d.HasMember("dead_cameras") && d["dead_cameras"].IsArray()) {
    for (const auto& v : d["dead_cameras"].GetArray()) {
      if (v.IsInt()) m.dead_cameras.push_back(v.GetInt());
    }
  }
  if (d.HasMember("counts") && d["counts"].IsObject()) {
    const auto& c = d["counts"];
    if (c.HasMember("expected") && c["expected"].IsInt64()) m.expected = c["expected"].GetInt64();
    if (c.HasMember("written") && c["written"].IsInt64()) m.written = c["written"].GetInt64();
    if (c.HasMember("skipped") && c["skipped"].IsInt64()) m.skipped = c["skipped"].GetInt64();
  }
  if (d.HasMember("errors") && d["errors"].IsArray()) {
    for (const auto& e : d["errors"].GetArray()) {
      if (!e.IsObject() || !e.HasMember("file") || !e["file"].IsString())
        return bad("errors[] entry without file");
      InputError err;
      if (e.HasMember("input") && e["input"].IsString()) err.input = e["input"].GetString();
      if (e.HasMember("error") && e["error"].IsString()) err.error = e["error"].GetString();
      m.errors[e["file"].GetString()] = err;
    }
  }
  if (!d.HasMember("files") || !d["files"].IsObject()) return bad("missing files object");
  for (const auto& kv : d["files"].GetObject()) {
    const auto& v = kv.value;
    if (!v.IsObject() || !v.HasMember("crc32") || !v["crc32"].IsString() || !v.HasMember("size") ||
        !v["size"].IsUint64()) {
      return bad(std::string("files.") + kv.name.GetString() + ": needs crc32 and size");
    }
    FileEntry f;
    f.crc32 = static_cast<std::uint32_t>(std::stoul(v["crc32"].GetString(), nullptr, 16));
    f.size_bytes = v["size"].GetUint64();
    if (v.HasMember("seed") && v["seed"].IsUint64()) f.seed = v["seed"].GetUint64();
    if (v.HasMember("kind") && v["kind"].IsString()) f.kind = v["kind"].GetString();
    m.files[kv.name.GetString()] = f;
  }
  return m;
}

Result<Manifest> read_manifest(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status(StatusCode::kNotFound, "cannot open " + path);
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_manifest(ss.str(), path);
}

Status write_file_atomic(const std::string& path, const std::uint8_t* data, std::size_t size) {
  static std::atomic<std::uint64_t> counter{0};
  const auto slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash);
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::string tmp = dir + "/." + name + ".tmp-" + std::to_string(::getpid()) + "-" +
                          std::to_string(counter.fetch_add(1));
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) return Status(StatusCode::kIoError, "cannot create " + tmp);
  const bool ok = std::fwrite(data, 1, size, f) == size;
  const bool closed = std::fclose(f) == 0;
  if (!ok || !closed) {
    std::remove(tmp.c_str());
    return Status(StatusCode::kIoError, "write failed: " + tmp);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return Status(StatusCode::kIoError, "cannot rename " + tmp + " to " + path);
  }
  return Status::ok();
}

Status write_manifest_atomic(const std::string& path, const Manifest& m) {
  const std::string json = manifest_json(m);
  return write_file_atomic(path, reinterpret_cast<const std::uint8_t*>(json.data()), json.size());
}

}  // namespace faultline::exporter
