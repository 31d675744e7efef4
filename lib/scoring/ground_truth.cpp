// Ground-truth loading: the devkit's load_gt + box_velocity + add_center_dist inputs.
#include "scoring/ground_truth.hpp"

#include <cmath>
#include <filesystem>
#include <future>
#include <limits>
#include <unordered_set>

#include "nuscenes/schema.hpp"
#include "nuscenes/table_reader.hpp"
#include "scoring/detection_config.hpp"
#include "scoring/token_set.hpp"

namespace faultline::scoring {
namespace {

namespace schema = nuscenes::schema;
using nuscenes::RecordFilter;
using nuscenes::stream_table;
using nuscenes::TableField;
using nuscenes::TableRecord;

struct SampleRec {
  std::string token;
  double timestamp_us = 0;
};

struct AnnRec {
  std::string token, prev, next, instance;
  int sample = -1;
  std::vector<std::string> attrs;
  std::array<double, 3> translation{}, size{};
  std::array<double, 4> rotation{};
  double num_pts = 0;
};

Status need(const TableRecord& r, std::size_t i, const std::string& path, std::size_t index,
            const char* name) {
  if (!r.fields[i].present) {
    return Status(StatusCode::kCorruptData,
                  path + ": record " + std::to_string(index) + " has no field '" + name + "'");
  }
  return Status::ok();
}

template <std::size_t N>
Status copy_vec(const TableField& f, std::array<double, N>& out, const std::string& where) {
  if (f.nums.size() != N) {
    return Status(StatusCode::kCorruptData, where + ": expected " + std::to_string(N) + " numbers");
  }
  for (std::size_t i = 0; i < N; ++i) out[i] = f.nums[i];
  return Status::ok();
}

// scene names -> tokens, then the split's samples in sample.json order.
Status load_samples(const std::string& dataroot, const std::string& version,
                    const std::vector<std::string>& scenes, std::vector<SampleRec>& samples) {
  const std::unordered_set<std::string> wanted(scenes.begin(), scenes.end());
  std::unordered_set<std::string> scene_tokens;
  const std::string scene_path = schema::table_path(dataroot, version, schema::kScene);
  using Scene = schema::TokenName;
  Status s = stream_table(scene_path, Scene::fields(), [&](const TableRecord& r, std::size_t i) {
    if (Status e = need(r, Scene::kToken, scene_path, i, "token"); !e) return e;
    if (Status e = need(r, Scene::kName, scene_path, i, "name"); !e) return e;
    if (wanted.count(r.fields[Scene::kName].str)) scene_tokens.insert(r.fields[Scene::kToken].str);
    return Status::ok();
  });
  if (!s) return s;
  const std::string sample_path = schema::table_path(dataroot, version, schema::kSample);
  using Sample = schema::ScoringSample;
  return stream_table(sample_path, Sample::fields(), [&](const TableRecord& r, std::size_t i) {
    for (std::size_t k = 0; k < Sample::fields().size(); ++k) {
      if (Status e = need(r, k, sample_path, i, Sample::fields()[k].c_str()); !e) return e;
    }
    if (scene_tokens.count(r.fields[Sample::kSceneToken].str)) {
      samples.push_back({r.fields[Sample::kToken].str, r.fields[Sample::kTimestamp].num});
    }
    return Status::ok();
  });
}

// Category, attribute and instance names (small tables), with their paths for errors.
struct Names {
  TokenMap<std::string> category_name, attribute_name, instance_category;
  std::string cat_path, attr_path, inst_path;
};

Status load_names(const std::string& dataroot, const std::string& version, Names& names) {
  names.cat_path = schema::table_path(dataroot, version, schema::kCategory);
  using Named = schema::TokenName;
  Status s = stream_table(names.cat_path, Named::fields(), [&](const TableRecord& r, std::size_t) {
    names.category_name[r.fields[Named::kToken].str] = r.fields[Named::kName].str;
    return Status::ok();
  });
  if (!s) return s;
  names.attr_path = schema::table_path(dataroot, version, schema::kAttribute);
  s = stream_table(names.attr_path, Named::fields(), [&](const TableRecord& r, std::size_t) {
    names.attribute_name[r.fields[Named::kToken].str] = r.fields[Named::kName].str;
    return Status::ok();
  });
  if (!s) return s;
  names.inst_path = schema::table_path(dataroot, version, schema::kInstance);
  using Instance = schema::InstanceCategory;
  s = stream_table(names.inst_path, Instance::fields(), [&](const TableRecord& r, std::size_t) {
    names.instance_category[r.fields[Instance::kToken].str] =
        r.fields[Instance::kCategoryToken].str;
    return Status::ok();
  });
  if (!s) return s;
  return Status::ok();
}

// The annotations of the split's samples (`sample_index`), in file order, indexed by token. Records
// of other samples are skipped undecoded.
Status scan_annotations(const std::string& ann_path, const TokenMap<int>& sample_index,
                        const TokenSet& split_set, std::vector<AnnRec>& anns,
                        TokenMap<int>& ann_index) {
  const auto in_split = [&split_set](const std::string& token) {
    return split_set.contains(token);
  };
  {
    // ~480 bytes per record in nuScenes tables; reserving avoids rehashing 1M-entry maps.
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(ann_path, ec);
    if (!ec) ann_index.reserve(static_cast<std::size_t>(bytes / 480));
  }
  using Ann = schema::ScoringAnnotation;
  const std::vector<std::string>& ann_fields = Ann::fields();
  Status scan = stream_table(
      ann_path, ann_fields,
      [&](const TableRecord& r, std::size_t i) {
        auto it = sample_index.find(r.fields[Ann::kSampleToken].str);
        if (it == sample_index.end()) return Status::ok();
        for (std::size_t k = 0; k < ann_fields.size(); ++k) {
          if (Status e = need(r, k, ann_path, i, ann_fields[k].c_str()); !e) return e;
        }
        AnnRec a;
        a.token = r.fields[Ann::kToken].str;
        a.sample = it->second;
        a.instance = r.fields[Ann::kInstanceToken].str;
        a.attrs = r.fields[Ann::kAttributeTokens].strs;
        const std::string where = ann_path + " record " + std::to_string(i) + " (" + a.token + ")";
        if (Status e = copy_vec(r.fields[Ann::kTranslation], a.translation, where + " translation");
            !e) {
          return e;
        }
        if (Status e = copy_vec(r.fields[Ann::kSize], a.size, where + " size"); !e) return e;
        if (Status e = copy_vec(r.fields[Ann::kRotation], a.rotation, where + " rotation"); !e)
          return e;
        a.num_pts = r.fields[Ann::kNumLidarPts].num + r.fields[Ann::kNumRadarPts].num;
        a.prev = r.fields[Ann::kPrev].str;
        a.next = r.fields[Ann::kNext].str;
        ann_index.emplace(a.token, static_cast<int>(anns.size()));
        anns.push_back(std::move(a));
        return Status::ok();
      },
      RecordFilter{{{static_cast<int>(Ann::kSampleToken), in_split}}});
  return scan;
}

// LIDAR_TOP calibrations -> key-frame sample_data -> ego pose of every split sample, into
// `ego_translation`.
Status load_ego_translations(const std::string& dataroot, const std::string& version,
                             const GroundTruth& gt, const std::vector<SampleRec>& samples,
                             const TokenSet& split_set,
                             std::vector<std::array<double, 3>>& ego_translation) {
  const std::size_t n = samples.size();
  const auto in_split = [&split_set](const std::string& token) {
    return split_set.contains(token);
  };
  std::unordered_set<std::string> lidar_sensors, lidar_calibs;
  const std::string sensor_path = schema::table_path(dataroot, version, schema::kSensor);
  using Sensor = schema::SensorChannel;
  Status s = stream_table(sensor_path, Sensor::fields(), [&](const TableRecord& r, std::size_t) {
    if (r.fields[Sensor::kChannel].str == "LIDAR_TOP")
      lidar_sensors.insert(r.fields[Sensor::kToken].str);
    return Status::ok();
  });
  if (!s) return s;
  const std::string calib_path = schema::table_path(dataroot, version, schema::kCalibratedSensor);
  using Calib = schema::CalibrationSensor;
  s = stream_table(calib_path, Calib::fields(), [&](const TableRecord& r, std::size_t) {
    if (lidar_sensors.count(r.fields[Calib::kSensorToken].str))
      lidar_calibs.insert(r.fields[Calib::kToken].str);
    return Status::ok();
  });
  if (!s) return s;
  const TokenSet lidar_calib_set(lidar_calibs);
  std::vector<std::string> pose_token(n);
  const std::string sd_path = schema::table_path(dataroot, version, schema::kSampleData);
  using Sd = schema::ScoringSampleData;
  s = stream_table(
      sd_path, Sd::fields(),
      [&](const TableRecord& r, std::size_t) {
        if (!r.fields[Sd::kIsKeyFrame].boolean) return Status::ok();
        auto it = gt.sample_index.find(r.fields[Sd::kSampleToken].str);
        if (it == gt.sample_index.end() ||
            !lidar_calibs.count(r.fields[Sd::kCalibratedSensorToken].str)) {
          return Status::ok();
        }
        pose_token[static_cast<std::size_t>(it->second)] =
            r.fields[Sd::kEgoPoseToken].str;  // last wins
        return Status::ok();
      },
      RecordFilter{{{static_cast<int>(Sd::kSampleToken), in_split},
                    {static_cast<int>(Sd::kCalibratedSensorToken),
                     [&lidar_calib_set](const std::string& calib) {
                       return lidar_calib_set.contains(calib);
                     }}}});
  if (!s) return s;
  TokenMap<std::vector<int>> pose_users;
  for (std::size_t i = 0; i < n; ++i) {
    if (pose_token[i].empty()) {
      return Status(StatusCode::kNotFound, sd_path + ": sample " + samples[i].token +
                                               " has no LIDAR_TOP key-frame sample_data record");
    }
    pose_users[pose_token[i]].push_back(static_cast<int>(i));
  }
  const TokenSet wanted_poses(pose_token);
  std::size_t poses_found = 0;
  const std::string pose_path = schema::table_path(dataroot, version, schema::kEgoPose);
  using Pose = schema::ScoringEgoPose;
  s = stream_table(
      pose_path, Pose::fields(),
      [&](const TableRecord& r, std::size_t i) {
        auto it = pose_users.find(r.fields[Pose::kToken].str);
        if (it == pose_users.end()) return Status::ok();
        std::array<double, 3> t{};
        if (Status e = copy_vec(r.fields[Pose::kTranslation], t,
                                pose_path + " record " + std::to_string(i) + " translation");
            !e) {
          return e;
        }
        for (int u : it->second) ego_translation[static_cast<std::size_t>(u)] = t;
        poses_found += it->second.size();
        pose_users.erase(it);  // a duplicated pose token counts once
        return Status::ok();
      },
      RecordFilter{{{static_cast<int>(Pose::kToken), [&wanted_poses](const std::string& token) {
                       return wanted_poses.contains(token);
                     }}}});
  if (!s) return s;
  if (poses_found < n) {
    return Status(StatusCode::kNotFound,
                  pose_path + ": " + std::to_string(n - poses_found) +
                      " LIDAR_TOP ego poses of the split's samples are missing");
  }
  return Status::ok();
}

// The evaluation boxes of the annotations (bicycle racks apart), with the devkit's box velocity.
Status build_boxes(const std::vector<AnnRec>& anns, const TokenMap<int>& ann_index,
                   const std::string& ann_path, const Names& names,
                   const std::vector<SampleRec>& samples, GroundTruth& gt) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto find_ann = [&](const std::string& token, const AnnRec& from) -> Result<const AnnRec*> {
    auto it = ann_index.find(token);
    if (it == ann_index.end()) {
      return Status(StatusCode::kNotFound,
                    ann_path + ": annotation " + from.token + " links to " + token +
                        ", which is not an annotation of the split's samples");
    }
    return &anns[static_cast<std::size_t>(it->second)];
  };
  for (const AnnRec& a : anns) {
    auto inst = names.instance_category.find(a.instance);
    if (inst == names.instance_category.end()) {
      return Status(StatusCode::kNotFound, names.inst_path + ": instance " + a.instance +
                                               " of annotation " + a.token + " not found");
    }
    auto cat = names.category_name.find(inst->second);
    if (cat == names.category_name.end()) {
      return Status(StatusCode::kNotFound,
                    names.cat_path + ": category " + inst->second + " not found");
    }
    const auto si = static_cast<std::size_t>(a.sample);
    if (cat->second == kBicycleRackCategory) {
      gt.racks[si].push_back({a.translation, a.size, a.rotation});
      continue;
    }
    auto cls = category_to_class(cat->second);
    if (!cls) continue;
    EvalBox box;
    box.cls = static_cast<std::int8_t>(*cls);
    if (a.attrs.size() > 1) {
      return Status(StatusCode::kCorruptData,
                    ann_path + ": annotation " + a.token +
                        ": Error: GT annotations must not have more than one attribute!");
    }
    if (a.attrs.size() == 1) {
      auto an = names.attribute_name.find(a.attrs[0]);
      if (an == names.attribute_name.end()) {
        return Status(StatusCode::kNotFound,
                      names.attr_path + ": attribute " + a.attrs[0] + " not found");
      }
      auto ai = attribute_index(an->second);
      if (!ai) {
        return Status(StatusCode::kCorruptData,
                      names.attr_path + ": unknown attribute name " + an->second);
      }
      box.attr = static_cast<std::int8_t>(*ai);
    }
    box.translation = a.translation;
    box.size = a.size;
    box.rotation = a.rotation;
    box.num_pts = static_cast<std::int32_t>(a.num_pts);
    box.score = -1.0;
    // Velocity (devkit box_velocity, max_time_diff 1.5 s, doubled for a centred difference).
    const bool has_prev = !a.prev.empty(), has_next = !a.next.empty();
    if (!has_prev && !has_next) {
      box.velocity = {nan, nan};
    } else {
      const AnnRec* first = &a;
      const AnnRec* last = &a;
      if (has_prev) {
        auto r = find_ann(a.prev, a);
        if (!r) return r.status();
        first = *r;
      }
      if (has_next) {
        auto r = find_ann(a.next, a);
        if (!r) return r.status();
        last = *r;
      }
      const double t_last = 1e-6 * samples[static_cast<std::size_t>(last->sample)].timestamp_us;
      const double t_first = 1e-6 * samples[static_cast<std::size_t>(first->sample)].timestamp_us;
      const double dt = t_last - t_first;
      const double limit = (has_prev && has_next) ? 3.0 : 1.5;
      if (dt > limit) {
        box.velocity = {nan, nan};
      } else {
        box.velocity = {(last->translation[0] - first->translation[0]) / dt,
                        (last->translation[1] - first->translation[1]) / dt};
      }
    }
    gt.boxes.boxes[si].push_back(box);
  }
  return Status::ok();
}

}  // namespace

Result<std::vector<std::string>> split_sample_tokens(const std::string& dataroot,
                                                     const std::string& version,
                                                     const std::vector<std::string>& scenes) {
  std::vector<SampleRec> samples;
  if (Status s = load_samples(dataroot, version, scenes, samples); !s) return s;
  std::vector<std::string> tokens;
  tokens.reserve(samples.size());
  for (auto& s : samples) tokens.push_back(std::move(s.token));
  return tokens;
}

Result<GroundTruth> load_ground_truth(const std::string& dataroot, const std::string& version,
                                      const std::vector<std::string>& scenes) {
  std::vector<SampleRec> samples;
  if (Status s = load_samples(dataroot, version, scenes, samples); !s) return s;
  GroundTruth gt;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    gt.sample_index.emplace(samples[i].token, static_cast<int>(i));
    gt.boxes.sample_tokens.push_back(samples[i].token);
  }
  const std::size_t n = samples.size();
  gt.boxes.boxes.resize(n);
  gt.racks.resize(n);
  gt.ego_translation.assign(n, {0, 0, 0});
  Names names;
  if (Status s = load_names(dataroot, version, names); !s) return s;

  // Records of other samples are skipped undecoded.
  const TokenSet split_set(gt.boxes.sample_tokens);
  // Annotations of the split's samples, in file order: the biggest scan after sample_data, so it
  // runs on a second thread while sample_data and ego_pose are read (it needs only the sample
  // index).
  std::vector<AnnRec> anns;
  TokenMap<int> ann_index;
  const std::string ann_path = schema::table_path(dataroot, version, schema::kSampleAnnotation);
  auto ann_future = std::async(std::launch::async, [&]() -> Status {
    return scan_annotations(ann_path, gt.sample_index, split_set, anns, ann_index);
  });
  // The annotation thread references this frame: wait for it before any return.
  Status poses =
      load_ego_translations(dataroot, version, gt, samples, split_set, gt.ego_translation);
  Status ann_status = ann_future.get();
  if (!poses) return poses;
  if (!ann_status) return ann_status;
  if (Status s = build_boxes(anns, ann_index, ann_path, names, samples, gt); !s) return s;
  return gt;
}

}  // namespace faultline::scoring
