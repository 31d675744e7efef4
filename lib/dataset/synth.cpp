// Synthetic nuScenes-format dataset: scene model -> tables (streamed per scene, synth_scene.cpp)
// and rendered camera JPEGs; here the static tables, logs, maps and the run over all scenes.
#include "dataset/synth.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>

#include "dataset/synth_scene.hpp"
#include "nuscenes/table_writer.hpp"

namespace faultline::dataset {
namespace synth_detail {

// Mounting close to the real nuScenes rig; camera key frames trail/lead the lidar sweep by tens of
// ms.
const std::vector<SensorSpec>& sensor_specs() {
  static const std::vector<SensorSpec> kSpecs = {
      {"CAM_FRONT", Modality::kCamera, {1.70, 0.016, 1.51}, 0, 1266.4, 12},
      {"CAM_FRONT_RIGHT", Modality::kCamera, {1.55, -0.49, 1.50}, -55, 1260.5, 20},
      {"CAM_FRONT_LEFT", Modality::kCamera, {1.52, 0.49, 1.51}, 55, 1272.6, 4},
      {"CAM_BACK", Modality::kCamera, {0.03, 0.0, 1.56}, 180, 800.0, 37},
      {"CAM_BACK_LEFT", Modality::kCamera, {1.04, 0.48, 1.57}, 110, 1256.7, 29},
      {"CAM_BACK_RIGHT", Modality::kCamera, {1.05, -0.48, 1.56}, -110, 1259.5, 33},
      {"LIDAR_TOP", Modality::kLidar, {0.985793, 0.0, 1.84019}, -90, 0, 0},
      {"RADAR_FRONT", Modality::kRadar, {3.41, 0.0, 0.50}, 0, 0, -21},
      {"RADAR_FRONT_LEFT", Modality::kRadar, {2.42, 0.80, 0.78}, 90, 0, -9},
      {"RADAR_FRONT_RIGHT", Modality::kRadar, {2.42, -0.80, 0.78}, -90, 0, 6},
      {"RADAR_BACK_LEFT", Modality::kRadar, {-0.56, 0.62, 0.53}, 180, 0, 17},
      {"RADAR_BACK_RIGHT", Modality::kRadar, {-0.56, -0.62, 0.53}, 180, 0, 28},
  };
  return kSpecs;
}

Status write_bytes(const std::filesystem::path& path, const std::vector<unsigned char>& bytes,
                   std::int64_t* total) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return Status(StatusCode::kIoError, path.string() + ": cannot create file");
  const std::size_t n = std::fwrite(bytes.data(), 1, bytes.size(), f);
  const bool ok = std::fclose(f) == 0 && n == bytes.size();
  if (!ok) return Status(StatusCode::kIoError, path.string() + ": write failed");
  *total += static_cast<std::int64_t>(bytes.size());
  return Status::ok();
}

}  // namespace synth_detail

namespace fs = std::filesystem;
using synth_detail::Modality;
using synth_detail::sensor_specs;
using synth_detail::SensorSpec;
using synth_detail::Shared;
using synth_detail::TokenSource;

namespace {

const char* modality_name(Modality m) {
  return m == Modality::kCamera ? "camera" : m == Modality::kLidar ? "lidar" : "radar";
}

const std::vector<const char*>& category_names() {  // the 23 nuScenes categories
  static const std::vector<const char*> kNames = {"animal",
                                                  "human.pedestrian.adult",
                                                  "human.pedestrian.child",
                                                  "human.pedestrian.construction_worker",
                                                  "human.pedestrian.personal_mobility",
                                                  "human.pedestrian.police_officer",
                                                  "human.pedestrian.stroller",
                                                  "human.pedestrian.wheelchair",
                                                  "movable_object.barrier",
                                                  "movable_object.debris",
                                                  "movable_object.pushable_pullable",
                                                  "movable_object.trafficcone",
                                                  "static_object.bicycle_rack",
                                                  "vehicle.bicycle",
                                                  "vehicle.bus.bendy",
                                                  "vehicle.bus.rigid",
                                                  "vehicle.car",
                                                  "vehicle.construction",
                                                  "vehicle.emergency.ambulance",
                                                  "vehicle.emergency.police",
                                                  "vehicle.motorcycle",
                                                  "vehicle.trailer",
                                                  "vehicle.truck"};
  return kNames;
}

const std::vector<const char*>& attribute_names() {
  static const std::vector<const char*> kNames = {
      "vehicle.moving",      "vehicle.stopped",     "vehicle.parked",
      "cycle.with_rider",    "cycle.without_rider", "pedestrian.sitting_lying_down",
      "pedestrian.standing", "pedestrian.moving"};
  return kNames;
}

struct Location {
  const char* name;
  const char* vehicle;
  int utc_offset_h;  // local = UTC + offset
};

const std::vector<Location>& locations() {
  static const std::vector<Location> kLocations = {{"boston-seaport", "n008", -4},
                                                   {"singapore-onenorth", "n015", 8},
                                                   {"singapore-queenstown", "n015", 8},
                                                   {"singapore-hollandvillage", "n015", 8}};
  return kLocations;
}

// Days since 1970-01-01 of a civil date (proleptic Gregorian).
std::int64_t days_from_civil(int y, int m, int d) {
  y -= m <= 2;
  const int era = (y >= 0 ? y : y - 399) / 400;
  const int yoe = y - era * 400;
  const int doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return static_cast<std::int64_t>(era) * 146097 + doe - 719468;
}

Status write_static_tables(Shared& sh) {
  auto& sensor = sh.tables["sensor"];
  for (std::size_t i = 0; i < sensor_specs().size(); ++i) {
    sh.sensor_tokens.push_back(sh.tokens.next());
    sensor.begin_record();
    sensor.field("token", sh.sensor_tokens.back());
    sensor.field("channel", sensor_specs()[i].channel);
    sensor.field("modality", modality_name(sensor_specs()[i].modality));
    sensor.end_record();
  }
  auto& category = sh.tables["category"];
  for (const char* name : category_names()) {
    sh.category_token[name] = sh.tokens.next();
    category.begin_record();
    category.field("token", sh.category_token[name]);
    category.field("name", name);
    category.field("description", std::string("Synthetic-set category ") + name + ".");
    category.end_record();
  }
  auto& attribute = sh.tables["attribute"];
  for (const char* name : attribute_names()) {
    sh.attribute_token[name] = sh.tokens.next();
    attribute.begin_record();
    attribute.field("token", sh.attribute_token[name]);
    attribute.field("name", name);
    attribute.field("description", std::string("Synthetic-set attribute ") + name + ".");
    attribute.end_record();
  }
  static const char* kLevels[4][2] = {
      {"v0-40", "visibility of whole object is between 0 and 40%"},
      {"v40-60", "visibility of whole object is between 40 and 60%"},
      {"v60-80", "visibility of whole object is between 60 and 80%"},
      {"v80-100", "visibility of whole object is between 80 and 100%"}};
  auto& visibility = sh.tables["visibility"];
  for (int i = 0; i < 4; ++i) {
    visibility.begin_record();
    visibility.field("token", std::to_string(i + 1));
    visibility.field("level", kLevels[i][0]);
    visibility.field("description", kLevels[i][1]);
    visibility.end_record();
  }
  return Status::ok();
}

// The options' ranges, checked before anything is written.
Status check_options(const SynthOptions& opt) {
  if (opt.out_dir.empty()) return Status(StatusCode::kInvalidArgument, "synth: out_dir is empty");
  if (opt.scenes < 1 || opt.scenes > 9999)
    return Status(StatusCode::kInvalidArgument, "synth: scenes must be 1..9999");
  if (!(opt.seconds >= 0.5 && opt.seconds <= 600)) {
    return Status(StatusCode::kInvalidArgument, "synth: seconds must be 0.5..600");
  }
  if (opt.image_width < 16 || opt.image_height < 16 || opt.jpeg_quality < 1 ||
      opt.jpeg_quality > 100) {
    return Status(StatusCode::kInvalidArgument, "synth: bad image size or JPEG quality");
  }
  if (opt.sensor_noise < 0 || opt.sensor_noise > 64) {
    return Status(StatusCode::kInvalidArgument,
                  "synth: sensor_noise = " + std::to_string(opt.sensor_noise) +
                      ": expected 0..64 (8-bit levels)");
  }
  if (opt.version.empty() || opt.version.find('/') != std::string::npos) {
    return Status(StatusCode::kInvalidArgument, "synth: bad version '" + opt.version + "'");
  }
  return Status::ok();
}

}  // namespace

std::string synth_scene_name(int index) {
  static const char* kMini[] = {"scene-0103", "scene-0916", "scene-0061", "scene-0553",
                                "scene-0655", "scene-0757", "scene-0796", "scene-1077",
                                "scene-1094", "scene-1100"};
  constexpr int kMiniCount = 10;
  if (index < kMiniCount) return kMini[index];
  std::set<int> used = {103, 916, 61, 553, 655, 757, 796, 1077, 1094, 1100};
  int number = 0;
  for (int i = kMiniCount; i <= index;) {
    ++number;
    if (!used.count(number)) ++i;
  }
  char buf[24];
  std::snprintf(buf, sizeof(buf), "scene-%04d", number);
  return buf;
}

Result<SynthSummary> write_synthetic_dataset(const SynthOptions& opt,
                                             const SynthProgressFn& progress) {
  const auto start = std::chrono::steady_clock::now();
  if (Status s = check_options(opt); !s) return s;
  Shared sh{opt,
            fs::path(opt.out_dir),
            TokenSource(opt.seed ^ 0x6E757363656E6573ULL),
            {},
            {},
            {},
            {},
            {},
            0,
            progress};
  std::error_code ec;
  const fs::path table_dir = sh.root / opt.version;
  fs::create_directories(table_dir, ec);
  fs::create_directories(sh.root / "maps", ec);
  if (!opt.metadata_only) {
    for (const auto& spec : sensor_specs()) {
      if (spec.modality != Modality::kCamera) continue;
      fs::create_directories(sh.root / "samples" / spec.channel, ec);
      fs::create_directories(sh.root / "sweeps" / spec.channel, ec);
    }
  }
  if (ec)
    return Status(StatusCode::kIoError,
                  sh.root.string() + ": cannot create folders: " + ec.message());
  for (const char* t :
       {"scene", "sample", "sample_data", "ego_pose", "calibrated_sensor", "sensor", "log", "map",
        "instance", "sample_annotation", "category", "attribute", "visibility"}) {
    if (Status s = sh.tables[t].open((table_dir / (std::string(t) + ".json")).string()); !s)
      return s;
  }
  if (Status s = write_static_tables(sh); !s) return s;

  // Logs: one per scene, each at a location; one map per location used.
  std::mt19937_64 log_rng(opt.seed + 0x1F2E3D4C);
  std::map<int, std::vector<std::string>> logs_at;
  const int images_per_scene_estimate = static_cast<int>(std::floor(opt.seconds * 12 + 4)) * 6;
  sh.images_total =
      opt.metadata_only ? 0 : static_cast<std::int64_t>(images_per_scene_estimate) * opt.scenes;
  for (int i = 0; i < opt.scenes; ++i) {
    const int loc = static_cast<int>(log_rng() % locations().size());
    const Location& L = locations()[static_cast<std::size_t>(loc)];
    const int month = 7 + static_cast<int>(log_rng() % 3),
              day = 1 + static_cast<int>(log_rng() % 28);
    const int hour = 9 + static_cast<int>(log_rng() % 9), minute = static_cast<int>(log_rng() % 60),
              second = static_cast<int>(log_rng() % 60);
    char logfile[64], date[16];
    std::snprintf(logfile, sizeof(logfile), "%s-2018-%02d-%02d-%02d-%02d-%02d%+03d00", L.vehicle,
                  month, day, hour, minute, second, L.utc_offset_h);
    std::snprintf(date, sizeof(date), "2018-%02d-%02d", month, day);
    const std::int64_t local_s =
        days_from_civil(2018, month, day) * 86400 + hour * 3600 + minute * 60 + second;
    const std::int64_t t0_us =
        (local_s - L.utc_offset_h * 3600 + 30 + static_cast<std::int64_t>(log_rng() % 600)) *
            1000000 +
        static_cast<std::int64_t>(log_rng() % 1000000);
    const std::string log_token = sh.tokens.next();
    auto& log = sh.tables["log"];
    log.begin_record();
    log.field("token", log_token);
    log.field("logfile", logfile);
    log.field("vehicle", L.vehicle);
    log.field("date_captured", date);
    log.field("location", L.name);
    log.end_record();
    logs_at[loc].push_back(log_token);
    if (Status s = synth_detail::write_scene(sh, i, log_token, logfile, t0_us); !s) return s;
    if (progress && opt.metadata_only && ((i + 1) % 50 == 0 || i + 1 == opt.scenes)) {
      progress("scenes", i + 1, opt.scenes);
    }
  }
  if (progress && sh.summary.images_written >
                      0) {  // the per-scene total above is an estimate; end on the real count
    progress("images", sh.summary.images_written, sh.summary.images_written);
  }
  auto& map = sh.tables["map"];
  std::vector<unsigned char> png;
  cv::imencode(".png", cv::Mat(2, 2, CV_8UC1, cv::Scalar(0)), png);
  for (const auto& [loc, tokens] : logs_at) {
    const std::string token = sh.tokens.next();
    const std::string filename = "maps/" + token + ".png";
    map.begin_record();
    map.field("token", token);
    map.field("log_tokens", tokens);
    map.field("category", "semantic_prior");
    map.field("filename", filename);
    map.end_record();
    if (Status s = synth_detail::write_bytes(sh.root / filename, png, &sh.summary.bytes_written);
        !s)
      return s;
  }
  for (auto& [name, writer] : sh.tables.writers) {
    if (Status s = writer.close(); !s) return s;
    sh.summary.bytes_written += writer.bytes();
  }
  sh.summary.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return sh.summary;
}

double camera_trigger_offset_ms(std::string_view channel) {
  for (const SensorSpec& spec : sensor_specs()) {
    if (spec.modality == Modality::kCamera && channel == spec.channel) return spec.offset_ms;
  }
  return 0;
}

}  // namespace faultline::dataset
