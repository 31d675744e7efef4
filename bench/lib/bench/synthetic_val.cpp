// Synthetic val-sized tables, written through the one table writer (nuscenes/table_writer.hpp) in
// its compact layout, and a submission.
#include "bench/synthetic_val.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <random>
#include <vector>

#include "nuscenes/schema.hpp"
#include "nuscenes/table_writer.hpp"
#include "scoring/detection_config.hpp"
#include "scoring/splits.hpp"

namespace faultline::bench {
namespace {

using scoring::kAttributeNames;
using scoring::kClassNames;
using scoring::kNumClasses;
using scoring::predefined_split_scenes;
using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;
using nuscenes::Number;
using nuscenes::TableWriter;
namespace schema = nuscenes::schema;

class Tokens {
 public:
  explicit Tokens(std::uint64_t seed) : state_(seed) {}
  std::string next() {
    char b[40];
    std::snprintf(b, sizeof b, "%016llx%016llx", static_cast<unsigned long long>(mix()),
                  static_cast<unsigned long long>(mix()));
    return b;
  }

 private:
  std::uint64_t mix() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  std::uint64_t state_;
};

// The tables of one synthetic set, each open for writing in the compact layout (one record per
// line).
class Tables {
 public:
  explicit Tables(std::string dir) : dir_(std::move(dir)) {}
  // Opens <dir>/<table>.json; the first failure is kept and returned by close_all().
  TableWriter& open(const char* table) {
    auto& w = writers_.emplace_back(std::make_unique<TableWriter>(nuscenes::TableLayout::kCompact));
    if (Status s = w->open(dir_ + "/" + table + ".json"); !s && first_error_.is_ok())
      first_error_ = s;
    return *w;
  }
  bool failed() const { return !first_error_.is_ok(); }
  Status close_all() {
    for (auto& w : writers_) {
      if (Status s = w->close(); !s && first_error_.is_ok()) first_error_ = s;
    }
    writers_.clear();
    return first_error_;
  }

 private:
  std::string dir_;
  std::vector<std::unique_ptr<TableWriter>> writers_;
  Status first_error_;
};

// One record of the token/name/description tables (category, attribute).
void named_record(TableWriter& w, const std::string& token, const char* name) {
  w.begin_record();
  w.field("token", token);
  w.field("name", name);
  w.field("description", "synthetic");
  w.end_record();
}

struct Category {
  const char* name;
  int cls;  // -1 for non-detection categories
  double w, l, h;
};

const Category kCategories[] = {{"vehicle.car", 0, 1.9, 4.6, 1.7},
                                {"vehicle.truck", 1, 2.5, 7.5, 3.0},
                                {"vehicle.bus.rigid", 2, 2.9, 11.0, 3.4},
                                {"vehicle.trailer", 3, 2.8, 10.0, 3.8},
                                {"vehicle.construction", 4, 2.8, 6.5, 3.2},
                                {"human.pedestrian.adult", 5, 0.7, 0.7, 1.75},
                                {"vehicle.motorcycle", 6, 0.8, 2.1, 1.5},
                                {"vehicle.bicycle", 7, 0.6, 1.7, 1.3},
                                {"movable_object.trafficcone", 8, 0.4, 0.4, 1.0},
                                {"movable_object.barrier", 9, 2.1, 0.5, 1.0},
                                {"static_object.bicycle_rack", -1, 2.0, 6.0, 1.2},
                                {"animal", -1, 0.4, 0.8, 0.6}};
// Relative frequency of each category among the objects.
const double kWeights[] = {30, 6, 2, 2, 2, 20, 3, 3, 14, 14, 1, 1};

int attribute_for(int cls, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> pick(0, 2);
  if (cls <= 4) return 5 + pick(rng);                  // vehicle.*
  if (cls == 5) return pick(rng);                      // pedestrian.*
  if (cls == 6 || cls == 7) return 3 + pick(rng) % 2;  // cycle.*
  return -1;
}

// Token of record i of one channel in one scene: a pure function, so prev/next links need no
// lookahead.
std::string channel_token(std::uint64_t seed, int scene, int channel, int i) {
  // Injective for scene < 1e6, channel < 16, i < 2^32 (the odd multiplier is a bijection mod 2^64).
  const std::uint64_t sc = (seed * 1000003ULL + static_cast<std::uint64_t>(scene)) * 16 +
                           static_cast<std::uint64_t>(channel);
  Tokens t(sc * 4294967311ULL + static_cast<std::uint64_t>(i));
  return t.next();
}

}  // namespace

Result<SyntheticValStats> write_synthetic_val(const std::string& dir,
                                              const SyntheticValConfig& cfg) {
  auto scenes_r = predefined_split_scenes("val", "v1.0-trainval");
  if (!scenes_r) return scenes_r.status();
  const auto& scene_names = *scenes_r;
  const std::string tdir = dir + "/v1.0-trainval";
  std::error_code ec;
  std::filesystem::create_directories(tdir, ec);
  if (ec) return Status(StatusCode::kIoError, tdir + ": " + ec.message());
  std::mt19937_64 rng(cfg.seed);
  Tokens tok(cfg.seed * 31 + 7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unif(0.0, 1.0);
  std::discrete_distribution<int> pick_cat(std::begin(kWeights), std::end(kWeights));

  // Small tables.
  Tables small(tdir);
  std::vector<std::string> cat_tokens, attr_tokens;
  TableWriter& category_w = small.open(schema::kCategory);
  if (small.failed()) return small.close_all();
  for (const auto& c : kCategories) {
    cat_tokens.push_back(tok.next());
    named_record(category_w, cat_tokens.back(), c.name);
  }
  TableWriter& attribute_w = small.open(schema::kAttribute);
  for (const char* a : kAttributeNames) {
    attr_tokens.push_back(tok.next());
    named_record(attribute_w, attr_tokens.back(), a);
  }
  TableWriter& visibility_w = small.open(schema::kVisibility);
  for (int v = 1; v <= 4; ++v) {
    visibility_w.begin_record();
    visibility_w.field("token", std::to_string(v));
    visibility_w.field("level", "v" + std::to_string(v));
    visibility_w.field("description", "synthetic");
    visibility_w.end_record();
  }
  const char* channels[] = {"CAM_FRONT",         "CAM_FRONT_RIGHT", "CAM_FRONT_LEFT",
                            "CAM_BACK",          "CAM_BACK_LEFT",   "CAM_BACK_RIGHT",
                            "LIDAR_TOP",         "RADAR_FRONT",     "RADAR_FRONT_LEFT",
                            "RADAR_FRONT_RIGHT", "RADAR_BACK_LEFT", "RADAR_BACK_RIGHT"};
  std::vector<std::string> sensor_tokens;
  TableWriter& sensor_w = small.open(schema::kSensor);
  for (const char* ch : channels) {
    sensor_tokens.push_back(tok.next());
    sensor_w.begin_record();
    sensor_w.field("token", sensor_tokens.back());
    sensor_w.field("channel", ch);
    sensor_w.field("modality", ch[0] == 'C' ? "camera" : (ch[0] == 'L' ? "lidar" : "radar"));
    sensor_w.end_record();
  }
  if (Status s = small.close_all(); !s) return s;
  // Scenes in name order, as scene.json lists them; val scenes also get predictions.
  std::vector<std::pair<std::string, bool>> scene_list;
  for (const auto& n : scene_names) scene_list.emplace_back(n, true);
  if (cfg.full_trainval) {
    auto train = predefined_split_scenes("train", "v1.0-trainval");
    if (!train) return train.status();
    for (const auto& n : *train) scene_list.emplace_back(n, false);
    std::sort(scene_list.begin(), scene_list.end());
  }
  const int n_val = static_cast<int>(scene_names.size());
  const int n_train = static_cast<int>(scene_list.size()) - n_val;
  const int n_scenes = static_cast<int>(scene_list.size());
  SyntheticValStats stats;
  stats.scenes = n_scenes;
  // Frames per 0.5 s sample period for each channel (12 Hz cameras, 20 Hz LIDAR, ~13 Hz radar).
  const int frames_per_sample[] = {6, 6, 6, 6, 6, 6, 10, 7, 6, 7, 6, 7};

  Tables big(tdir);
  TableWriter &scene_w = big.open(schema::kScene), &log_w = big.open(schema::kLog),
              &calib_w = big.open(schema::kCalibratedSensor), &sample_w = big.open(schema::kSample),
              &sd_w = big.open(schema::kSampleData), &pose_w = big.open(schema::kEgoPose),
              &inst_w = big.open(schema::kInstance), &ann_w = big.open(schema::kSampleAnnotation);
  if (big.failed()) return big.close_all();
  File res(std::fopen((dir + "/results.json").c_str(), "wb"), &std::fclose);
  if (!res) return Status(StatusCode::kIoError, dir + "/results.json: cannot write");
  std::fputs(
      "{\"meta\": {\"use_camera\": true, \"use_lidar\": false, \"use_radar\": false, \"use_map\": "
      "false, "
      "\"use_external\": false}, \"results\": {\n",
      res.get());
  std::vector<std::string> log_tokens;
  std::size_t results_written = 0;
  int val_seen = 0, train_seen = 0;
  for (int s = 0; s < n_scenes; ++s) {
    const bool is_val = scene_list[static_cast<std::size_t>(s)].second;
    const int n_samples =
        is_val ? cfg.samples / n_val + (val_seen < cfg.samples % n_val ? 1 : 0)
               : cfg.train_samples / n_train + (train_seen < cfg.train_samples % n_train ? 1 : 0);
    (is_val ? val_seen : train_seen)++;
    const int n_objects = is_val ? cfg.objects_per_scene : cfg.train_objects_per_scene;
    const std::string scene_tok = tok.next(), log_tok = tok.next();
    std::vector<std::string> calib_toks;
    for (std::size_t c = 0; c < std::size(channels); ++c) calib_toks.push_back(tok.next());
    log_tokens.push_back(log_tok);
    std::vector<std::string> sample_toks(static_cast<std::size_t>(n_samples));
    for (auto& t : sample_toks) t = tok.next();
    char logfile[32];
    std::snprintf(logfile, sizeof logfile, "n000-synthetic-%03d", s);
    log_w.begin_record();
    log_w.field("token", log_tok);
    log_w.field("logfile", logfile);
    log_w.field("vehicle", "n000");
    log_w.field("date_captured", "2018-08-01");
    log_w.field("location", "boston-seaport");
    log_w.end_record();
    scene_w.begin_record();
    scene_w.field("token", scene_tok);
    scene_w.field("log_token", log_tok);
    scene_w.field("nbr_samples", n_samples);
    scene_w.field("first_sample_token", sample_toks.front());
    scene_w.field("last_sample_token", sample_toks.back());
    scene_w.field("name", scene_list[static_cast<std::size_t>(s)].first);
    scene_w.field("description", std::string("synthetic ") + (is_val ? "val" : "train") + " scene");
    scene_w.end_record();
    for (std::size_t c = 0; c < std::size(channels); ++c) {
      calib_w.begin_record();
      calib_w.field("token", calib_toks[c]);
      calib_w.field("sensor_token", sensor_tokens[c]);
      calib_w.field("translation", std::vector<double>{0.94, 0.0, 1.84});
      calib_w.field("rotation", std::vector<double>{0.7071, 0.0, 0.0, -0.7071});
      if (c < 6) {
        calib_w.matrix("camera_intrinsic",
                       {{1266.4, 0.0, 816.3}, {0.0, 1266.4, 491.5}, {0.0, 0.0, 1.0}});
      } else {
        calib_w.matrix("camera_intrinsic", {});
      }
      calib_w.end_record();
    }
    // Ego drives straight along a random heading at a random speed.
    const double ex0 = 300 + 2000 * unif(rng), ey0 = 300 + 2000 * unif(rng),
                 heading = 2 * M_PI * unif(rng);
    const double speed = 8 * unif(rng);
    const long long t0 = 1533000000000000LL + static_cast<long long>(s) * 100000000LL;
    std::vector<long long> ts(static_cast<std::size_t>(n_samples));
    std::vector<std::array<double, 2>> ego(static_cast<std::size_t>(n_samples));
    for (int k = 0; k < n_samples; ++k) {
      const auto uk = static_cast<std::size_t>(k);
      ts[uk] = t0 + static_cast<long long>(k) * 500000LL + static_cast<long long>(unif(rng) * 4000);
      const double d = speed * 0.5 * k;
      ego[uk] = {ex0 + d * std::cos(heading), ey0 + d * std::sin(heading)};
      sample_w.begin_record();
      sample_w.field("token", sample_toks[uk]);
      sample_w.field("timestamp", static_cast<std::int64_t>(ts[uk]));
      sample_w.field("prev", k ? sample_toks[uk - 1] : std::string());
      sample_w.field("next", k + 1 < n_samples ? sample_toks[uk + 1] : std::string());
      sample_w.field("scene_token", scene_tok);
      sample_w.end_record();
    }
    // sample_data + ego_pose, one pose per record with the record's token, channel by channel. The
    // key frame of each channel opens each sample period; sweeps follow it (without sweeps: LIDAR
    // key frames).
    for (std::size_t c = 0; c < std::size(channels); ++c) {
      if (!cfg.sweeps && c != 6) continue;
      const int per_sample = cfg.sweeps ? frames_per_sample[c] : 1;
      const int total = n_samples * per_sample;
      auto sd_token = [&](int i) { return channel_token(cfg.seed, s, static_cast<int>(c), i); };
      std::string prev, cur = sd_token(0), next;
      for (int i = 0; i < total; ++i) {
        next = i + 1 < total ? sd_token(i + 1) : std::string();
        const int k = i / per_sample, f = i % per_sample;
        const auto uk = static_cast<std::size_t>(k);
        const long long t = ts[uk] + static_cast<long long>(f) * 500000LL / per_sample;
        const double d = speed * (1e-6 * static_cast<double>(t - t0));
        const bool camera = c < 6, lidar = c == 6;
        char filename[128];
        std::snprintf(filename, sizeof filename, "%s/%s/n000-synthetic-%03d__%s__%lld.%s",
                      f == 0 ? "samples" : "sweeps", channels[c], s, channels[c], t,
                      camera ? "jpg" : (lidar ? "pcd.bin" : "pcd"));
        sd_w.begin_record();
        sd_w.field("token", cur);
        sd_w.field("sample_token", sample_toks[uk]);
        sd_w.field("ego_pose_token", cur);
        sd_w.field("calibrated_sensor_token", calib_toks[c]);
        sd_w.field("timestamp", static_cast<std::int64_t>(t));
        sd_w.field("fileformat", camera ? "jpg" : "pcd");
        sd_w.field("is_key_frame", f == 0);
        sd_w.field("height", camera ? 900 : 0);
        sd_w.field("width", camera ? 1600 : 0);
        sd_w.field("filename", filename);
        sd_w.field("prev", prev);
        sd_w.field("next", next);
        sd_w.end_record();
        pose_w.begin_record();
        pose_w.field("token", cur);
        pose_w.field("timestamp", static_cast<std::int64_t>(t));
        pose_w.field("rotation", {Number{std::cos(heading / 2), 9}, Number{0.0}, Number{0.0},
                                  Number{std::sin(heading / 2), 9}});
        pose_w.field("translation", {Number{ex0 + d * std::cos(heading), 6},
                                     Number{ey0 + d * std::sin(heading), 6}, Number{0.0}});
        pose_w.end_record();
        ++stats.sample_data;
        prev = std::move(cur);
        cur = std::move(next);
      }
    }
    // Objects: each is annotated in every sample of the scene.
    struct Obj {
      int cat;
      double x0, y0, vx, vy, yaw, w, l, h;
      int attr;
      std::string inst;
      std::vector<std::string> anns;
    };
    std::vector<Obj> objs(static_cast<std::size_t>(n_objects));
    const double mid = speed * 0.5 * (n_samples - 1) / 2;
    for (auto& o : objs) {
      o.cat = pick_cat(rng);
      const Category& c = kCategories[o.cat];
      const double r = 5 + 40 * std::sqrt(unif(rng)), a = 2 * M_PI * unif(rng);
      o.x0 = ex0 + mid * std::cos(heading) + r * std::cos(a);
      o.y0 = ey0 + mid * std::sin(heading) + r * std::sin(a);
      const bool moving = c.cls >= 0 && c.cls <= 7 && unif(rng) < 0.4;
      o.yaw = 2 * M_PI * unif(rng) - M_PI;
      const double v = moving ? (c.cls == 5 ? 1.4 : 6.0) * unif(rng) : 0.0;
      o.vx = v * std::cos(o.yaw);
      o.vy = v * std::sin(o.yaw);
      o.w = c.w * (0.9 + 0.2 * unif(rng));
      o.l = c.l * (0.9 + 0.2 * unif(rng));
      o.h = c.h * (0.9 + 0.2 * unif(rng));
      o.attr = c.cls >= 0 ? attribute_for(c.cls, rng) : -1;
      o.anns.resize(static_cast<std::size_t>(n_samples));
      for (auto& t : o.anns) t = tok.next();
      o.inst = tok.next();
      inst_w.begin_record();
      inst_w.field("token", o.inst);
      inst_w.field("category_token", cat_tokens[static_cast<std::size_t>(o.cat)]);
      inst_w.field("nbr_annotations", n_samples);
      inst_w.field("first_annotation_token", o.anns.front());
      inst_w.field("last_annotation_token", o.anns.back());
      inst_w.end_record();
    }
    for (int k = 0; k < n_samples; ++k) {
      const auto uk = static_cast<std::size_t>(k);
      if (is_val) {
        std::fprintf(res.get(), "%s\"%s\": [", results_written++ ? ",\n" : "",
                     sample_toks[uk].c_str());
      }
      int boxes_in_sample = 0;
      auto emit_pred = [&](int cls, double x, double y, double z, double w, double l, double h,
                           double yaw, double vx, double vy, int attr, double score) {
        std::fprintf(res.get(),
                     "%s{\"sample_token\": \"%s\", \"translation\": [%.4f, %.4f, %.4f], \"size\": "
                     "[%.3f, %.3f, %.3f], "
                     "\"rotation\": [%.6f, 0.0, 0.0, %.6f], \"velocity\": [%.3f, %.3f], "
                     "\"detection_name\": \"%s\", "
                     "\"detection_score\": %.5f, \"attribute_name\": \"%s\"}",
                     boxes_in_sample++ ? ", " : "", sample_toks[uk].c_str(), x, y, z, w, l, h,
                     std::cos(yaw / 2), std::sin(yaw / 2), vx, vy,
                     kClassNames[static_cast<std::size_t>(cls)], score,
                     attr >= 0 ? kAttributeNames[static_cast<std::size_t>(attr)] : "");
        ++stats.predictions;
      };
      for (auto& o : objs) {
        const Category& c = kCategories[o.cat];
        const double t = 0.5 * k;
        const double x = o.x0 + o.vx * t, y = o.y0 + o.vy * t, z = o.h / 2;
        const int lidar = unif(rng) < 0.04 ? 0 : 1 + static_cast<int>(200 * unif(rng));
        ann_w.begin_record();
        ann_w.field("token", o.anns[uk]);
        ann_w.field("sample_token", sample_toks[uk]);
        ann_w.field("instance_token", o.inst);
        ann_w.field("visibility_token", "4");
        ann_w.field("attribute_tokens",
                    o.attr >= 0
                        ? std::vector<std::string>{attr_tokens[static_cast<std::size_t>(o.attr)]}
                        : std::vector<std::string>{});
        ann_w.field("translation", std::vector<double>{x, y, z}, 6);
        ann_w.field("size", std::vector<double>{o.w, o.l, o.h}, 3);
        ann_w.field("rotation", {Number{std::cos(o.yaw / 2), 9}, Number{0.0}, Number{0.0},
                                 Number{std::sin(o.yaw / 2), 9}});
        ann_w.field("prev", k ? o.anns[uk - 1] : std::string());
        ann_w.field("next", k + 1 < n_samples ? o.anns[uk + 1] : std::string());
        ann_w.field("num_lidar_pts", lidar);
        ann_w.field("num_radar_pts", static_cast<int>(5 * unif(rng)));
        ann_w.end_record();
        ++stats.annotations;
        if (!is_val || c.cls < 0 || unif(rng) > cfg.detection_rate) continue;
        const double noise = 0.3 + 0.5 * unif(rng);
        emit_pred(c.cls, x + noise * gauss(rng), y + noise * gauss(rng), z + 0.1 * gauss(rng),
                  o.w * (1 + 0.05 * gauss(rng)), o.l * (1 + 0.05 * gauss(rng)),
                  o.h * (1 + 0.05 * gauss(rng)), o.yaw + 0.15 * gauss(rng), o.vx + 0.5 * gauss(rng),
                  o.vy + 0.5 * gauss(rng), unif(rng) < 0.9 ? o.attr : attribute_for(c.cls, rng),
                  0.3 + 0.7 * unif(rng) / (1 + noise));
      }
      if (!is_val) continue;
      for (int f = 0; f < cfg.false_positives; ++f) {
        const int cls = static_cast<int>(unif(rng) * kNumClasses) % kNumClasses;
        const double r = 45 * std::sqrt(unif(rng)), a = 2 * M_PI * unif(rng);
        emit_pred(cls, ego[uk][0] + r * std::cos(a), ego[uk][1] + r * std::sin(a), 1.0, 2, 4, 1.6,
                  a, 0, 0, attribute_for(cls, rng), 0.4 * unif(rng));
      }
      std::fputs("]", res.get());
    }
    if (is_val) stats.samples += n_samples;
  }
  std::fputs("\n}}\n", res.get());
  if (Status s = big.close_all(); !s) return s;
  TableWriter& map_w = small.open(schema::kMap);
  map_w.begin_record();
  map_w.field("token", tok.next());
  map_w.field("log_tokens", log_tokens);
  map_w.field("category", "semantic_prior");
  map_w.field("filename", "maps/synthetic.png");
  map_w.end_record();
  if (Status s = small.close_all(); !s) return s;
  return stats;
}

}  // namespace faultline::bench
