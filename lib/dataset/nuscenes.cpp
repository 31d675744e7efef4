// Scene-scoped nuScenes reader: DOM for the small tables, SAX streaming for sample_data and ego_pose.
#include "dataset/nuscenes.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <unordered_set>

#include "common/bounded_read.hpp"
#include "dataset/json_table.hpp"

namespace faultline::dataset {
namespace fs = std::filesystem;

const std::array<const char*, 6>& camera_channels() {
  static const std::array<const char*, 6> kChannels = {"CAM_FRONT", "CAM_FRONT_RIGHT", "CAM_FRONT_LEFT",
                                                       "CAM_BACK",  "CAM_BACK_LEFT",   "CAM_BACK_RIGHT"};
  return kChannels;
}

namespace {

int channel_rank(const std::string& channel) {
  const auto& channels = camera_channels();
  for (std::size_t i = 0; i < channels.size(); ++i) {
    if (channel == channels[i]) return static_cast<int>(i);
  }
  return static_cast<int>(channels.size());
}

Status bad_record(const std::string& path, rapidjson::SizeType index, const std::string& why) {
  return Status(StatusCode::kCorruptData, path + ": record " + std::to_string(index) + ": " + why);
}

// Field readers for DOM records; each returns false when the key is missing or mistyped.
bool dom_string(const rapidjson::Value& v, const char* key, std::string* out) {
  auto it = v.FindMember(key);
  if (it == v.MemberEnd() || !it->value.IsString()) return false;
  out->assign(it->value.GetString(), it->value.GetStringLength());
  return true;
}

bool dom_int(const rapidjson::Value& v, const char* key, std::int64_t* out) {
  auto it = v.FindMember(key);
  if (it == v.MemberEnd() || !it->value.IsInt64()) return false;
  *out = it->value.GetInt64();
  return true;
}

bool dom_numbers(const rapidjson::Value& v, const char* key, std::vector<double>* out) {
  auto it = v.FindMember(key);
  if (it == v.MemberEnd() || !it->value.IsArray()) return false;
  out->clear();
  for (const auto& e : it->value.GetArray()) {
    if (e.IsNumber()) {
      out->push_back(e.GetDouble());
    } else if (e.IsArray()) {  // camera_intrinsic is a list of rows
      for (const auto& x : e.GetArray()) {
        if (!x.IsNumber()) return false;
        out->push_back(x.GetDouble());
      }
    } else {
      return false;
    }
  }
  return true;
}

bool to_pose(const std::vector<double>& t, const std::vector<double>& r, Pose* pose) {
  if (t.size() != 3 || r.size() != 4) return false;
  std::copy(t.begin(), t.end(), pose->translation.begin());
  std::copy(r.begin(), r.end(), pose->rotation.begin());
  return true;
}

// Runs `fn(record, index)` over every record of a small table; the first failure names file and record.
template <typename Fn>
Status for_each_dom_record(const std::string& path, Fn&& fn) {
  rapidjson::Document doc;
  if (Status s = parse_document(path, &doc); !s) return s;
  for (rapidjson::SizeType i = 0; i < doc.Size(); ++i) {
    if (!doc[i].IsObject()) return bad_record(path, i, "not an object");
    if (Status s = fn(doc[i], i); !s) return s;
  }
  return Status::ok();
}

}  // namespace

std::string NuScenesReader::table_path(const std::string& table) const {
  return (fs::path(dataroot_) / version_ / (table + ".json")).string();
}

std::string NuScenesReader::path_of(const CameraFrameRecord& f) const {
  return (fs::path(dataroot_) / f.filename).string();
}

Result<NuScenesReader> NuScenesReader::open(const std::string& dataroot, const std::string& version) {
  NuScenesReader r;
  std::error_code ec;
  r.dataroot_ = fs::absolute(dataroot, ec).lexically_normal().string();
  if (!r.dataroot_.empty() && r.dataroot_.size() > 1 && r.dataroot_.back() == '/') r.dataroot_.pop_back();
  r.version_ = version;
  const fs::path dir = fs::path(r.dataroot_) / version;
  if (!fs::is_directory(dir, ec)) {
    return Status(StatusCode::kNotFound, dir.string() + ": nuScenes table folder not found");
  }
  for (const char* big : {"sample_data", "ego_pose"}) {
    if (!fs::is_regular_file(r.table_path(big), ec)) {
      return Status(StatusCode::kNotFound, r.table_path(big) + ": table not found");
    }
  }

  std::string path = r.table_path("scene");
  Status s = for_each_dom_record(path, [&](const rapidjson::Value& v, rapidjson::SizeType i) {
    SceneRecord sc;
    std::int64_t n = 0;
    if (!dom_string(v, "token", &sc.token) || !dom_string(v, "name", &sc.name) ||
        !dom_string(v, "log_token", &sc.log_token) || !dom_string(v, "first_sample_token", &sc.first_sample_token) ||
        !dom_string(v, "last_sample_token", &sc.last_sample_token) || !dom_int(v, "nbr_samples", &n)) {
      return bad_record(path, i, "missing or mistyped scene field");
    }
    dom_string(v, "description", &sc.description);
    sc.nbr_samples = static_cast<int>(n);
    r.scenes_.push_back(std::move(sc));
    return Status::ok();
  });
  if (!s) return s;

  path = r.table_path("sample");
  s = for_each_dom_record(path, [&](const rapidjson::Value& v, rapidjson::SizeType i) {
    SampleRecord sa;
    if (!dom_string(v, "token", &sa.token) || !dom_string(v, "scene_token", &sa.scene_token) ||
        !dom_string(v, "prev", &sa.prev) || !dom_string(v, "next", &sa.next) ||
        !dom_int(v, "timestamp", &sa.timestamp_us)) {
      return bad_record(path, i, "missing or mistyped sample field");
    }
    r.sample_index_.emplace(sa.token, r.samples_.size());
    r.samples_.push_back(std::move(sa));
    return Status::ok();
  });
  if (!s) return s;

  std::unordered_map<std::string, std::pair<std::string, std::string>> sensors;  // token -> channel, modality
  path = r.table_path("sensor");
  s = for_each_dom_record(path, [&](const rapidjson::Value& v, rapidjson::SizeType i) {
    std::string token, channel, modality;
    if (!dom_string(v, "token", &token) || !dom_string(v, "channel", &channel) ||
        !dom_string(v, "modality", &modality)) {
      return bad_record(path, i, "missing or mistyped sensor field");
    }
    sensors[token] = {channel, modality};
    return Status::ok();
  });
  if (!s) return s;

  path = r.table_path("calibrated_sensor");
  s = for_each_dom_record(path, [&](const rapidjson::Value& v, rapidjson::SizeType i) {
    std::string token, sensor_token;
    std::vector<double> t, q, k;
    Calibration c;
    if (!dom_string(v, "token", &token) || !dom_string(v, "sensor_token", &sensor_token) ||
        !dom_numbers(v, "translation", &t) || !dom_numbers(v, "rotation", &q) ||
        !dom_numbers(v, "camera_intrinsic", &k) || !to_pose(t, q, &c.sensor_to_ego)) {
      return bad_record(path, i, "missing or mistyped calibrated_sensor field");
    }
    auto it = sensors.find(sensor_token);
    if (it == sensors.end()) return bad_record(path, i, "unknown sensor_token " + sensor_token);
    c.channel = it->second.first;
    c.modality = it->second.second;
    if (c.modality == "camera") {
      if (k.size() != 9) return bad_record(path, i, "camera_intrinsic is not 3x3");
      std::copy(k.begin(), k.end(), c.intrinsics.begin());
    }
    r.calibrations_[token] = std::move(c);
    return Status::ok();
  });
  if (!s) return s;

  path = r.table_path("log");
  std::unordered_set<std::string> logs;
  s = for_each_dom_record(path, [&](const rapidjson::Value& v, rapidjson::SizeType i) {
    std::string token, logfile;
    if (!dom_string(v, "token", &token) || !dom_string(v, "logfile", &logfile)) {
      return bad_record(path, i, "missing or mistyped log field");
    }
    logs.insert(token);
    return Status::ok();
  });
  if (!s) return s;
  for (const auto& sc : r.scenes_) {
    if (!logs.count(sc.log_token)) {
      return Status(StatusCode::kCorruptData, r.table_path("scene") + ": " + sc.name + " has unknown log_token");
    }
  }
  return r;
}

Result<std::vector<const SceneRecord*>> NuScenesReader::resolve(const std::vector<std::string>& scene_names) const {
  std::vector<const SceneRecord*> out;
  if (scene_names.empty()) {
    for (const auto& sc : scenes_) out.push_back(&sc);
    return out;
  }
  for (const auto& name : scene_names) {
    auto it = std::find_if(scenes_.begin(), scenes_.end(), [&](const SceneRecord& sc) { return sc.name == name; });
    if (it == scenes_.end()) {
      std::string known;
      for (const auto& sc : scenes_) known += (known.empty() ? "" : ", ") + sc.name;
      return Status(StatusCode::kNotFound, "unknown scene '" + name + "' in " + table_path("scene") +
                                               "; known scenes: " + known);
    }
    out.push_back(&*it);
  }
  return out;
}

Result<std::vector<SampleRecord>> NuScenesReader::samples_of(const std::vector<std::string>& scene_names) const {
  auto selected = resolve(scene_names);
  if (!selected) return selected.status();
  std::unordered_set<std::string> tokens;
  for (const auto* sc : *selected) tokens.insert(sc->token);
  std::vector<SampleRecord> out;
  for (const auto& sa : samples_) {
    if (tokens.count(sa.scene_token)) out.push_back(sa);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const SampleRecord& a, const SampleRecord& b) { return a.timestamp_us < b.timestamp_us; });
  return out;
}

Result<std::vector<CameraFrameRecord>> NuScenesReader::load_camera_frames(
    const std::vector<std::string>& scene_names, const ProblemFn& on_problem) const {
  auto selected = resolve(scene_names);
  if (!selected) return selected.status();
  std::unordered_map<std::string, const SceneRecord*> scene_by_token;
  for (const auto* sc : *selected) scene_by_token[sc->token] = sc;

  // sample token -> scene, for the selected scenes only.
  std::unordered_map<std::string, const SceneRecord*> scene_of_sample;
  for (const auto& sa : samples_) {
    auto it = scene_by_token.find(sa.scene_token);
    if (it != scene_by_token.end()) scene_of_sample.emplace(sa.token, it->second);
  }

  std::vector<CameraFrameRecord> frames;
  std::unordered_map<std::string, std::size_t> frame_of_pose;  // ego_pose_token -> index in frames
  const std::string sd_path = table_path("sample_data");
  std::string sample_token, cs_token, pose_token;
  Status s = stream_table(sd_path, [&](const JsonRecord& rec) {
    if (!rec.get("sample_token", &sample_token)) {
      if (on_problem) on_problem(bad_record(sd_path, static_cast<rapidjson::SizeType>(rec.index()), "no sample_token"));
      return Status::ok();
    }
    auto scene_it = scene_of_sample.find(sample_token);
    if (scene_it == scene_of_sample.end()) return Status::ok();  // another scene
    const auto report = [&](const std::string& why) {
      if (on_problem) on_problem(bad_record(sd_path, static_cast<rapidjson::SizeType>(rec.index()), why));
      return Status::ok();
    };
    if (!rec.get("calibrated_sensor_token", &cs_token)) return report("no calibrated_sensor_token");
    auto cal_it = calibrations_.find(cs_token);
    if (cal_it == calibrations_.end()) return report("unknown calibrated_sensor_token " + cs_token);
    const Calibration& cal = cal_it->second;
    if (cal.modality != "camera") return Status::ok();
    CameraFrameRecord f;
    std::int64_t width = 0, height = 0;
    if (!rec.get("token", &f.sample_data_token) || !rec.get("filename", &f.filename) ||
        !rec.get("timestamp", &f.timestamp_us) || !rec.get("is_key_frame", &f.is_key_frame) ||
        !rec.get("width", &width) || !rec.get("height", &height) || !rec.get("ego_pose_token", &pose_token)) {
      return report("missing or mistyped sample_data field");
    }
    f.channel = cal.channel;
    f.sample_token = sample_token;
    f.scene_token = scene_it->second->token;
    f.scene_name = scene_it->second->name;
    f.width = static_cast<int>(width);
    f.height = static_cast<int>(height);
    f.intrinsics = cal.intrinsics;
    f.sensor_to_ego = cal.sensor_to_ego;
    if (!frame_of_pose.emplace(pose_token, frames.size()).second) {
      return report("ego_pose_token " + pose_token + " shared by two camera frames");
    }
    frames.push_back(std::move(f));
    return Status::ok();
  });
  if (!s) return s;

  const std::string pose_path = table_path("ego_pose");
  std::vector<bool> posed(frames.size(), false);
  std::string token;
  std::vector<double> t, q;
  s = stream_table(pose_path, [&](const JsonRecord& rec) {
    if (!rec.get("token", &token)) return Status::ok();
    auto it = frame_of_pose.find(token);
    if (it == frame_of_pose.end()) return Status::ok();
    if (!rec.get_numbers("translation", &t) || !rec.get_numbers("rotation", &q) ||
        !to_pose(t, q, &frames[it->second].ego_pose)) {
      if (on_problem) {
        on_problem(bad_record(pose_path, static_cast<rapidjson::SizeType>(rec.index()), "bad translation/rotation"));
      }
      return Status::ok();
    }
    posed[it->second] = true;
    return Status::ok();
  });
  if (!s) return s;

  // Frames without an ego pose cannot be placed in the world: report and drop them.
  std::size_t kept = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (!posed[i]) {
      if (on_problem) {
        on_problem(Status(StatusCode::kNotFound,
                          pose_path + ": no ego_pose for sample_data " + frames[i].sample_data_token));
      }
      continue;
    }
    if (kept != i) frames[kept] = std::move(frames[i]);
    ++kept;
  }
  frames.resize(kept);
  std::sort(frames.begin(), frames.end(), [](const CameraFrameRecord& a, const CameraFrameRecord& b) {
    if (a.timestamp_us != b.timestamp_us) return a.timestamp_us < b.timestamp_us;
    const int ra = channel_rank(a.channel), rb = channel_rank(b.channel);
    if (ra != rb) return ra < rb;
    return a.sample_data_token < b.sample_data_token;
  });
  return frames;
}

Result<std::map<std::string, SceneFrameCounts>> NuScenesReader::count_frames(const ProblemFn& on_problem) const {
  std::map<std::string, SceneFrameCounts> counts;
  for (const auto& sc : scenes_) counts[sc.token];
  const std::string sd_path = table_path("sample_data");
  std::string sample_token, cs_token;
  Status s = stream_table(sd_path, [&](const JsonRecord& rec) {
    bool key = false;
    if (!rec.get("sample_token", &sample_token) || !rec.get("calibrated_sensor_token", &cs_token) ||
        !rec.get("is_key_frame", &key)) {
      if (on_problem) on_problem(bad_record(sd_path, static_cast<rapidjson::SizeType>(rec.index()), "bad record"));
      return Status::ok();
    }
    auto sa = sample_index_.find(sample_token);
    auto cal = calibrations_.find(cs_token);
    if (sa == sample_index_.end() || cal == calibrations_.end()) {
      if (on_problem) {
        on_problem(bad_record(sd_path, static_cast<rapidjson::SizeType>(rec.index()), "unknown sample or sensor"));
      }
      return Status::ok();
    }
    SceneFrameCounts& c = counts[samples_[sa->second].scene_token];
    if (cal->second.modality == "camera") {
      ++c.camera_frames;
      c.camera_key_frames += key ? 1 : 0;
    } else {
      ++c.other_frames;
    }
    return Status::ok();
  });
  if (!s) return s;
  return counts;
}

Result<std::vector<std::uint8_t>> read_file(const std::string& path, std::size_t max_bytes) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) return Status(StatusCode::kNotFound, path + ": file not found");
  std::vector<std::uint8_t> data;
  std::uint8_t buf[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof(buf), file.get())) > 0) {
    if (data.size() + n > max_bytes) {
      return Status(StatusCode::kInvalidArgument, path + ": larger than the limit of " + describe_bytes(max_bytes) +
                                                      " (" + std::to_string(max_bytes) + " bytes)");
    }
    data.insert(data.end(), buf, buf + n);
  }
  if (std::ferror(file.get())) return Status(StatusCode::kIoError, path + ": read failed");
  return data;
}

}  // namespace faultline::dataset
