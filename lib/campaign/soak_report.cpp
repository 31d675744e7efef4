// What a soak run writes: each loop's detections as a nuScenes submission, the periods as log
// lines, soak.json and periods.csv.
#include "campaign/soak_report.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace faultline::campaign::soak_detail {

std::string fmt(double v, int prec) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", prec, std::isfinite(v) ? v : 0.0);
  return b;
}

namespace {

std::string json_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    o += c;
  }
  return o;
}

}  // namespace

Status write_loop_results(const std::string& path, const std::vector<std::string>& split_samples,
                          const std::unordered_map<std::string, msgs::DetectionArray>& got) {
  std::ofstream out(path, std::ios::binary);
  if (!out) return Status(StatusCode::kIoError, path + ": cannot write");
  out << "{\"meta\": {\"use_camera\": true, \"use_lidar\": false, \"use_radar\": false, "
         "\"use_map\": false, "
         "\"use_external\": false}, \"results\": {";
  char num[64];
  auto put = [&](double v) {
    std::snprintf(num, sizeof num, "%.9g", std::isfinite(v) ? v : 0.0);
    out << num;
  };
  auto list = [&](const google::protobuf::RepeatedField<double>& v) {
    out << "[";
    for (int i = 0; i < v.size(); ++i) {
      if (i) out << ", ";
      put(v[i]);
    }
    out << "]";
  };
  for (std::size_t s = 0; s < split_samples.size(); ++s) {
    out << (s ? ",\n" : "\n") << "\"" << split_samples[s] << "\": [";
    auto it = got.find(split_samples[s]);
    if (it != got.end()) {
      int k = 0;
      for (const auto& d : it->second.detections()) {
        if (k++) out << ", ";
        out << "{\"sample_token\": \"" << split_samples[s] << "\", \"translation\": ";
        list(d.translation());
        out << ", \"size\": ";
        list(d.size());
        out << ", \"rotation\": ";
        list(d.rotation());
        out << ", \"velocity\": ";
        list(d.velocity());
        out << ", \"detection_name\": \"" << json_escape(d.detection_name())
            << "\", \"detection_score\": ";
        put(d.detection_score());
        out << ", \"attribute_name\": \"" << json_escape(d.attribute_name()) << "\"}";
      }
    }
    out << "]";
  }
  out << "\n}}\n";
  out.close();
  return out ? Status::ok() : Status(StatusCode::kIoError, path + ": write failed");
}

std::string period_line(const SoakPeriod& p) {
  std::uint64_t in = 0, out = 0;
  for (const auto& [k, v] : p.frames_in) in += v;
  for (const auto& [k, v] : p.frames_out) out += v;
  std::string mem;
  for (const auto& m : p.memory) mem += " " + m.node + "=" + fmt(m.rss_mb, 1) + "MB";
  return "period " + std::to_string(p.index) + " @" + fmt(p.end_s, 0) + "s: frames in " +
         std::to_string(in) + " out " + std::to_string(out) + ", unintended drops " +
         std::to_string(p.transport_drops) + ", injected drops " +
         std::to_string(p.injected_drops) + ", samples " + std::to_string(p.samples_published) +
         " -> detections " + std::to_string(p.detection_arrays) + ", latency p50/p99 " +
         fmt(p.latency_ms_p50, 1) + "/" + fmt(p.latency_ms_p99, 1) + " ms, continuity " +
         (p.continuity < 0 ? std::string("n/a") : fmt(p.continuity, 3)) + ", RSS" + mem;
}

std::string soak_json(const SoakOptions& o, const SoakResult& r) {
  std::ostringstream js;
  js << "{\n  \"dataroot\": \"" << json_escape(o.dataroot) << "\", \"version\": \"" << o.version
     << "\", \"eval_set\": \"" << o.eval_set << "\",\n  \"duration_s\": " << fmt(o.duration_s, 1)
     << ", \"period_s\": " << fmt(o.period_s, 1) << ", \"rate\": " << fmt(o.rate, 3)
     << ", \"corruption\": \"" << json_escape(o.corruption) << "\", \"injector_params_file\": \""
     << json_escape(o.injector_params_file) << "\",\n  \"detector\": \""
     << json_escape(o.detector_cmd.empty() ? "faultline detector" : o.detector_cmd)
     << "\",\n  \"rss_growth_mb\": " << fmt(r.rss_growth_mb, 1) << ",\n  \"node_failures\": [";
  for (std::size_t i = 0; i < r.node_failures.size(); ++i) {
    js << (i ? ", " : "") << "\"" << json_escape(r.node_failures[i]) << "\"";
  }
  js << "],\n  \"periods\": [";
  for (std::size_t i = 0; i < r.periods.size(); ++i) {
    const auto& p = r.periods[i];
    js << (i ? "," : "") << "\n    {\"index\": " << p.index << ", \"end_s\": " << fmt(p.end_s, 1)
       << ", \"frames_in\": {";
    int k = 0;
    for (const auto& [cam, n] : p.frames_in) js << (k++ ? ", " : "") << "\"" << cam << "\": " << n;
    js << "}, \"frames_out\": {";
    k = 0;
    for (const auto& [cam, n] : p.frames_out) js << (k++ ? ", " : "") << "\"" << cam << "\": " << n;
    js << "}, \"unintended_drops\": " << p.transport_drops << ", \"superseded\": " << p.superseded
       << ", \"injected_drops\": " << p.injected_drops
       << ", \"samples_published\": " << p.samples_published
       << ", \"detection_arrays\": " << p.detection_arrays << ", \"malformed\": " << p.malformed
       << ", \"latency_ms_p50\": " << fmt(p.latency_ms_p50, 2)
       << ", \"latency_ms_p99\": " << fmt(p.latency_ms_p99, 2) << ", \"track_continuity\": "
       << (p.continuity < 0 ? std::string("null") : fmt(p.continuity, 4)) << ", \"rss_mb\": {";
    k = 0;
    for (const auto& m : p.memory)
      js << (k++ ? ", " : "") << "\"" << json_escape(m.node) << "\": " << fmt(m.rss_mb, 1);
    js << "}}";
  }
  js << "\n  ],\n  \"loops\": [";
  for (std::size_t i = 0; i < r.loops.size(); ++i) {
    const auto& l = r.loops[i];
    js << (i ? "," : "") << "\n    {\"index\": " << l.index << ", \"samples\": " << l.samples
       << ", \"samples_with_detections\": " << l.samples_with_detections
       << ", \"scored\": " << (l.scored ? "true" : "false") << ", \"nds\": " << fmt(l.nds, 4)
       << ", \"map\": " << fmt(l.map, 4) << ", \"error\": \"" << json_escape(l.error) << "\"}";
  }
  js << "\n  ]\n}\n";
  return js.str();
}

std::string periods_csv(const SoakResult& r) {
  std::ostringstream csv;
  csv << "period,end_s,frames_in,frames_out,unintended_drops,injected_drops,samples,detections,"
         "latency_ms_p50,"
         "latency_ms_p99,continuity,rss_mb_total\n";
  for (const auto& p : r.periods) {
    std::uint64_t in = 0, out = 0;
    for (const auto& [k, v] : p.frames_in) in += v;
    for (const auto& [k, v] : p.frames_out) out += v;
    double rss = 0;
    for (const auto& m : p.memory) rss += m.rss_mb;
    csv << p.index << "," << fmt(p.end_s, 1) << "," << in << "," << out << "," << p.transport_drops
        << "," << p.injected_drops << "," << p.samples_published << "," << p.detection_arrays << ","
        << fmt(p.latency_ms_p50, 2) << "," << fmt(p.latency_ms_p99, 2) << ","
        << fmt(p.continuity, 4) << "," << fmt(rss, 1) << "\n";
  }
  return csv.str();
}

}  // namespace faultline::campaign::soak_detail
