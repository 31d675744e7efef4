// Scene-scoped nuScenes reader: every table is read with nuscenes::stream_table (the one table
// reader), the small ones whole at open(), sample_data and ego_pose per request keeping only the
// selected scenes' records.
#include "dataset/nuscenes.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <unordered_set>

#include "common/bounded_read.hpp"
#include "nuscenes/schema.hpp"
#include "nuscenes/table_reader.hpp"

namespace faultline::dataset {
namespace fs = std::filesystem;
namespace schema = nuscenes::schema;
using Fields = std::vector<nuscenes::TableField>;

const std::array<const char*, 6>& camera_channels() {
  static const std::array<const char*, 6> kChannels = {"CAM_FRONT",      "CAM_FRONT_RIGHT",
                                                       "CAM_FRONT_LEFT", "CAM_BACK",
                                                       "CAM_BACK_LEFT",  "CAM_BACK_RIGHT"};
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

Status bad_record(const std::string& path, std::size_t index, const std::string& why) {
  return Status(StatusCode::kCorruptData, path + ": record " + std::to_string(index) + ": " + why);
}

bool to_pose(const std::vector<double>& t, const std::vector<double>& r, Pose* pose) {
  if (t.size() != 3 || r.size() != 4) return false;
  std::copy(t.begin(), t.end(), pose->translation.begin());
  std::copy(r.begin(), r.end(), pose->rotation.begin());
  return true;
}

// Runs `fn(fields, index)` over every record of a small table, read with `View`'s fields. Every
// element of the array must be a record (the reader skips other elements; the gap in the indices
// reveals them); the first failure names the file and the record.
template <typename View, typename Fn>
Status for_each_record(const std::string& path, Fn&& fn) {
  std::size_t next = 0;
  Status s = nuscenes::stream_table(path, View::fields(),
                                    [&](const nuscenes::TableRecord& r, std::size_t i) {
                                      if (i != next) return bad_record(path, next, "not an object");
                                      ++next;
                                      return fn(r.fields, i);
                                    });
  if (!s) return s;
  return Status::ok();
}

}  // namespace

std::string NuScenesReader::table_path(const std::string& table) const {
  return (fs::path(dataroot_) / version_ / (table + ".json")).string();
}

std::string NuScenesReader::path_of(const CameraFrameRecord& f) const {
  return (fs::path(dataroot_) / f.filename).string();
}

Result<NuScenesReader> NuScenesReader::open(const std::string& dataroot,
                                            const std::string& version) {
  NuScenesReader r;
  std::error_code ec;
  r.dataroot_ = fs::absolute(dataroot, ec).lexically_normal().string();
  if (!r.dataroot_.empty() && r.dataroot_.size() > 1 && r.dataroot_.back() == '/')
    r.dataroot_.pop_back();
  r.version_ = version;
  const fs::path dir = fs::path(r.dataroot_) / version;
  if (!fs::is_directory(dir, ec)) {
    return Status(StatusCode::kNotFound, dir.string() + ": nuScenes table folder not found");
  }
  for (const char* big : {schema::kSampleData, schema::kEgoPose}) {
    if (!fs::is_regular_file(r.table_path(big), ec)) {
      return Status(StatusCode::kNotFound, r.table_path(big) + ": table not found");
    }
  }
  if (Status s = r.load_scenes(); !s) return s;
  if (Status s = r.load_samples(); !s) return s;
  if (Status s = r.load_calibrations(); !s) return s;
  if (Status s = r.check_logs(); !s) return s;
  return r;
}

Status NuScenesReader::load_scenes() {
  using V = schema::ReplayScene;
  const std::string path = table_path(schema::kScene);
  return for_each_record<V>(path, [&](const Fields& f, std::size_t i) {
    SceneRecord sc;
    std::int64_t n = 0;
    if (!f[V::kToken].get(&sc.token) || !f[V::kName].get(&sc.name) ||
        !f[V::kLogToken].get(&sc.log_token) ||
        !f[V::kFirstSampleToken].get(&sc.first_sample_token) ||
        !f[V::kLastSampleToken].get(&sc.last_sample_token) || !f[V::kNbrSamples].get(&n)) {
      return bad_record(path, i, "missing or mistyped scene field");
    }
    f[V::kDescription].get(&sc.description);
    sc.nbr_samples = static_cast<int>(n);
    scenes_.push_back(std::move(sc));
    return Status::ok();
  });
}

Status NuScenesReader::load_samples() {
  using V = schema::ReplaySample;
  const std::string path = table_path(schema::kSample);
  return for_each_record<V>(path, [&](const Fields& f, std::size_t i) {
    SampleRecord sa;
    if (!f[V::kToken].get(&sa.token) || !f[V::kSceneToken].get(&sa.scene_token) ||
        !f[V::kPrev].get(&sa.prev) || !f[V::kNext].get(&sa.next) ||
        !f[V::kTimestamp].get(&sa.timestamp_us)) {
      return bad_record(path, i, "missing or mistyped sample field");
    }
    sample_index_.emplace(sa.token, samples_.size());
    samples_.push_back(std::move(sa));
    return Status::ok();
  });
}

Status NuScenesReader::load_calibrations() {
  std::unordered_map<std::string, std::pair<std::string, std::string>>
      sensors;  // token -> channel, modality
  std::string path = table_path(schema::kSensor);
  Status s = for_each_record<schema::ReplaySensor>(path, [&](const Fields& f, std::size_t i) {
    using V = schema::ReplaySensor;
    std::string token, channel, modality;
    if (!f[V::kToken].get(&token) || !f[V::kChannel].get(&channel) ||
        !f[V::kModality].get(&modality)) {
      return bad_record(path, i, "missing or mistyped sensor field");
    }
    sensors[token] = {channel, modality};
    return Status::ok();
  });
  if (!s) return s;
  path = table_path(schema::kCalibratedSensor);
  std::vector<double> t, q, k;
  return for_each_record<schema::ReplayCalibration>(path, [&](const Fields& f, std::size_t i) {
    using V = schema::ReplayCalibration;
    std::string token, sensor_token;
    Calibration c;
    if (!f[V::kToken].get(&token) || !f[V::kSensorToken].get(&sensor_token) ||
        !f[V::kTranslation].get_numbers(&t) || !f[V::kRotation].get_numbers(&q) ||
        !f[V::kCameraIntrinsic].get_numbers(&k) || !to_pose(t, q, &c.sensor_to_ego)) {
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
    calibrations_[token] = std::move(c);
    return Status::ok();
  });
}

Status NuScenesReader::check_logs() const {
  const std::string path = table_path(schema::kLog);
  std::unordered_set<std::string> logs;
  Status s = for_each_record<schema::ReplayLog>(path, [&](const Fields& f, std::size_t i) {
    using V = schema::ReplayLog;
    std::string token, logfile;
    if (!f[V::kToken].get(&token) || !f[V::kLogfile].get(&logfile)) {
      return bad_record(path, i, "missing or mistyped log field");
    }
    logs.insert(token);
    return Status::ok();
  });
  if (!s) return s;
  for (const auto& sc : scenes_) {
    if (!logs.count(sc.log_token)) {
      return Status(StatusCode::kCorruptData,
                    table_path(schema::kScene) + ": " + sc.name + " has unknown log_token");
    }
  }
  return Status::ok();
}
Result<std::vector<const SceneRecord*>> NuScenesReader::resolve(
    const std::vector<std::string>& scene_names) const {
  std::vector<const SceneRecord*> out;
  if (scene_names.empty()) {
    for (const auto& sc : scenes_) out.push_back(&sc);
    return out;
  }
  for (const auto& name : scene_names) {
    auto it = std::find_if(scenes_.begin(), scenes_.end(),
                           [&](const SceneRecord& sc) { return sc.name == name; });
    if (it == scenes_.end()) {
      std::string known;
      for (const auto& sc : scenes_) known += (known.empty() ? "" : ", ") + sc.name;
      return Status(StatusCode::kNotFound, "unknown scene '" + name + "' in " +
                                               table_path("scene") + "; known scenes: " + known);
    }
    out.push_back(&*it);
  }
  return out;
}

Result<std::vector<SampleRecord>> NuScenesReader::samples_of(
    const std::vector<std::string>& scene_names) const {
  auto selected = resolve(scene_names);
  if (!selected) return selected.status();
  std::unordered_set<std::string> tokens;
  for (const auto* sc : *selected) tokens.insert(sc->token);
  std::vector<SampleRecord> out;
  for (const auto& sa : samples_) {
    if (tokens.count(sa.scene_token)) out.push_back(sa);
  }
  std::stable_sort(out.begin(), out.end(), [](const SampleRecord& a, const SampleRecord& b) {
    return a.timestamp_us < b.timestamp_us;
  });
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
  if (Status s = stream_camera_frames(scene_of_sample, on_problem, frames, frame_of_pose); !s)
    return s;
  if (Status s = attach_ego_poses(frame_of_pose, on_problem, frames); !s) return s;
  std::sort(frames.begin(), frames.end(),
            [](const CameraFrameRecord& a, const CameraFrameRecord& b) {
              if (a.timestamp_us != b.timestamp_us) return a.timestamp_us < b.timestamp_us;
              const int ra = channel_rank(a.channel), rb = channel_rank(b.channel);
              if (ra != rb) return ra < rb;
              return a.sample_data_token < b.sample_data_token;
            });
  return frames;
}

Status NuScenesReader::stream_camera_frames(
    const std::unordered_map<std::string, const SceneRecord*>& scene_of_sample,
    const ProblemFn& on_problem, std::vector<CameraFrameRecord>& frames,
    std::unordered_map<std::string, std::size_t>& frame_of_pose) const {
  using V = schema::ReplaySampleData;
  const std::string sd_path = table_path(schema::kSampleData);
  std::string sample_token, cs_token, pose_token;
  // Records of other scenes are skipped undecoded; those without a string sample_token reach the
  // callback, which reports them.
  const nuscenes::RecordFilter other_scenes{
      {{static_cast<int>(V::kSampleToken), [&](const std::string& token) {
          return token.empty() || scene_of_sample.count(token) != 0;
        }}}};
  return nuscenes::stream_table(
      sd_path, V::fields(),
      [&](const nuscenes::TableRecord& rec, std::size_t index) {
        const Fields& f = rec.fields;
        const auto report = [&](const std::string& why) {
          if (on_problem) on_problem(bad_record(sd_path, index, why));
          return Status::ok();
        };
        if (!f[V::kSampleToken].get(&sample_token)) return report("no sample_token");
        auto scene_it = scene_of_sample.find(sample_token);
        if (scene_it == scene_of_sample.end()) return Status::ok();  // another scene
        if (!f[V::kCalibratedSensorToken].get(&cs_token))
          return report("no calibrated_sensor_token");
        auto cal_it = calibrations_.find(cs_token);
        if (cal_it == calibrations_.end())
          return report("unknown calibrated_sensor_token " + cs_token);
        const Calibration& cal = cal_it->second;
        if (cal.modality != "camera") return Status::ok();
        CameraFrameRecord fr;
        std::int64_t width = 0, height = 0;
        if (!f[V::kToken].get(&fr.sample_data_token) || !f[V::kFilename].get(&fr.filename) ||
            !f[V::kTimestamp].get(&fr.timestamp_us) || !f[V::kIsKeyFrame].get(&fr.is_key_frame) ||
            !f[V::kWidth].get(&width) || !f[V::kHeight].get(&height) ||
            !f[V::kEgoPoseToken].get(&pose_token)) {
          return report("missing or mistyped sample_data field");
        }
        fr.channel = cal.channel;
        fr.sample_token = sample_token;
        fr.scene_token = scene_it->second->token;
        fr.scene_name = scene_it->second->name;
        fr.width = static_cast<int>(width);
        fr.height = static_cast<int>(height);
        fr.intrinsics = cal.intrinsics;
        fr.sensor_to_ego = cal.sensor_to_ego;
        if (!frame_of_pose.emplace(pose_token, frames.size()).second) {
          return report("ego_pose_token " + pose_token + " shared by two camera frames");
        }
        frames.push_back(std::move(fr));
        return Status::ok();
      },
      other_scenes);
}

Status NuScenesReader::attach_ego_poses(
    const std::unordered_map<std::string, std::size_t>& frame_of_pose, const ProblemFn& on_problem,
    std::vector<CameraFrameRecord>& frames) const {
  using V = schema::ReplayEgoPose;
  const std::string pose_path = table_path(schema::kEgoPose);
  std::vector<bool> posed(frames.size(), false);
  std::string token;
  std::vector<double> t, q;
  const nuscenes::RecordFilter other_poses{
      {{static_cast<int>(V::kToken),
        [&](const std::string& pose) { return frame_of_pose.count(pose) != 0; }}}};
  Status s = nuscenes::stream_table(
      pose_path, V::fields(),
      [&](const nuscenes::TableRecord& rec, std::size_t index) {
        const Fields& f = rec.fields;
        if (!f[V::kToken].get(&token)) return Status::ok();
        auto it = frame_of_pose.find(token);
        if (it == frame_of_pose.end()) return Status::ok();
        if (!f[V::kTranslation].get_numbers(&t) || !f[V::kRotation].get_numbers(&q) ||
            !to_pose(t, q, &frames[it->second].ego_pose)) {
          if (on_problem) on_problem(bad_record(pose_path, index, "bad translation/rotation"));
          return Status::ok();
        }
        posed[it->second] = true;
        return Status::ok();
      },
      other_poses);
  if (!s) return s;
  // Frames without an ego pose cannot be placed in the world: report and drop them.
  std::size_t kept = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (!posed[i]) {
      if (on_problem) {
        on_problem(Status(StatusCode::kNotFound, pose_path + ": no ego_pose for sample_data " +
                                                     frames[i].sample_data_token));
      }
      continue;
    }
    if (kept != i) frames[kept] = std::move(frames[i]);
    ++kept;
  }
  frames.resize(kept);
  return Status::ok();
}

Result<std::map<std::string, SceneFrameCounts>> NuScenesReader::count_frames(
    const ProblemFn& on_problem) const {
  using V = schema::FrameCountSampleData;
  std::map<std::string, SceneFrameCounts> counts;
  for (const auto& sc : scenes_) counts[sc.token];
  const std::string sd_path = table_path(schema::kSampleData);
  std::string sample_token, cs_token;
  Status s = nuscenes::stream_table(
      sd_path, V::fields(), [&](const nuscenes::TableRecord& rec, std::size_t index) {
        const Fields& f = rec.fields;
        bool key = false;
        if (!f[V::kSampleToken].get(&sample_token) ||
            !f[V::kCalibratedSensorToken].get(&cs_token) || !f[V::kIsKeyFrame].get(&key)) {
          if (on_problem) on_problem(bad_record(sd_path, index, "bad record"));
          return Status::ok();
        }
        auto sa = sample_index_.find(sample_token);
        auto cal = calibrations_.find(cs_token);
        if (sa == sample_index_.end() || cal == calibrations_.end()) {
          if (on_problem) on_problem(bad_record(sd_path, index, "unknown sample or sensor"));
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
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (!file) return Status(StatusCode::kNotFound, path + ": file not found");
  std::vector<std::uint8_t> data;
  std::uint8_t buf[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof(buf), file.get())) > 0) {
    if (data.size() + n > max_bytes) {
      return Status(StatusCode::kInvalidArgument, path + ": larger than the limit of " +
                                                      describe_bytes(max_bytes) + " (" +
                                                      std::to_string(max_bytes) + " bytes)");
    }
    data.insert(data.end(), buf, buf + n);
  }
  if (std::ferror(file.get())) return Status(StatusCode::kIoError, path + ": read failed");
  return data;
}

}  // namespace faultline::dataset
