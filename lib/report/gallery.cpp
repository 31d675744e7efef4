// The corruption gallery: tiles, strips, the gallery directory and its index, the report's
// thumbnails.
#include "report/gallery.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgproc.hpp>

#include "codec/jpeg.hpp"
#include "corruption/catalogue.hpp"
#include "corruption/corrupt.hpp"
#include "dataset/synth_frame.hpp"

namespace faultline::report {
namespace fs = std::filesystem;
using corruption::Corruption;

namespace {

constexpr int kGapPx = 2;  // white between the tiles of a strip

std::string fmt_g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::vector<Corruption> types_of(const GalleryOptions& options) {
  if (!options.types.empty()) return options.types;
  return {std::begin(corruption::kAllCorruptions), std::end(corruption::kAllCorruptions)};
}

// The label in a dark box in the tile's top-left corner, sized to the tile.
void draw_label(cv::Mat& tile, const std::string& label) {
  if (label.empty()) return;
  const double scale = std::max(0.3, tile.cols / 560.0);
  const int thickness = scale > 0.6 ? 2 : 1;
  int baseline = 0;
  const cv::Size text =
      cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
  const int pad = 3;
  const cv::Rect box(0, 0, std::min(tile.cols, text.width + 2 * pad),
                     std::min(tile.rows, text.height + baseline + 2 * pad));
  cv::rectangle(tile, box, cv::Scalar(32, 32, 32), cv::FILLED);
  cv::putText(tile, label, cv::Point(pad, pad + text.height), cv::FONT_HERSHEY_SIMPLEX, scale,
              cv::Scalar(255, 255, 255), thickness, cv::LINE_AA);
}

Status write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file.write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  file.close();
  if (!file) return Status(StatusCode::kIoError, "cannot write '" + path.string() + "'");
  return Status::ok();
}

// "1: σ 0.08 · 2: σ 0.12 · ...": the parameters of severities 1..5.
std::string parameters_line(Corruption type) {
  std::string line;
  for (int s = 1; s <= 5; ++s) {
    line +=
        (s > 1 ? " · " : "") + std::to_string(s) + ": " + corruption::severity_parameters(type, s);
  }
  return line;
}

std::string class_text(Corruption type) {
  std::string text = corruption::to_string(corruption::fidelity(type));
  const std::string note = corruption::fidelity_note(type);
  if (!note.empty()) text += "; " + note;
  return text;
}

// The thumbnail of one benchmark corruption.
CorruptionThumbnail thumbnail(const ThumbnailRequest& request,
                              const std::vector<std::string>& levels, const cv::Mat& frame,
                              const GalleryOptions& options) {
  CorruptionThumbnail t;
  t.name = request.name;
  const auto type = corruption::corruption_from_string(request.type);
  if (!type) {
    t.caption = request.name + ": drops or damages whole frames, not pixels: no picture";
    return t;
  }
  std::vector<int> severities;
  std::string shown;
  for (const auto& l : levels) {
    const auto level = corruption::level_from_string(l);
    if (!level) {
      t.caption = request.name + ": level '" + l + "' is not easy, mid or hard: no picture";
      return t;
    }
    severities.push_back(corruption::severity_for(*type, *level));
    shown += (shown.empty() ? "" : ", ") + l + " (" + std::to_string(severities.back()) + ")";
  }
  auto strip = gallery_strip(frame, *type, severities, levels, options);
  Result<std::vector<std::uint8_t>> jpeg = strip.status();
  if (strip) jpeg = codec::encode_jpeg(*strip, options.jpeg_quality);
  if (!jpeg) {
    t.caption = request.name + ": " + jpeg.status().message();
    return t;
  }
  t.jpeg = std::move(*jpeg);
  t.width = strip->cols;
  t.height = strip->rows;
  t.caption = request.name + " (" + request.type + "): " + shown;
  return t;
}

}  // namespace

Status validate(const GalleryOptions& options) {
  if (options.thumb_width < 16 || options.thumb_width > 1600) {
    return Status(StatusCode::kInvalidArgument, "gallery thumb width " +
                                                    std::to_string(options.thumb_width) +
                                                    ": expected 16..1600 pixels");
  }
  if (options.jpeg_quality < 1 || options.jpeg_quality > 100) {
    return Status(
        StatusCode::kInvalidArgument,
        "gallery JPEG quality " + std::to_string(options.jpeg_quality) + ": expected 1..100");
  }
  if (!std::isfinite(options.yaw_rate_deg_s)) {
    return Status(StatusCode::kInvalidArgument, "gallery yaw rate: expected a finite number");
  }
  return Status::ok();
}

cv::Mat gallery_frame() {
  return dataset::realistic_frame(kGalleryFrameWidth, kGalleryFrameHeight, kGalleryFrameSeed);
}

Result<cv::Mat> gallery_tile(const cv::Mat& frame, Corruption type, int severity,
                             const GalleryOptions& options) {
  if (Status s = validate(options); !s) return s;
  if (frame.empty() || frame.type() != CV_8UC3)
    return Status(StatusCode::kInvalidArgument, "gallery frame: expected a non-empty BGR image");
  cv::Mat corrupted = frame;
  if (severity != 0) {
    corruption::CorruptOptions co;
    co.yaw_rate_rad_s = options.yaw_rate_deg_s * M_PI / 180.0;
    auto out = corruption::corrupt_seeded(frame, type, severity, options.rng, options.seed, co);
    if (!out) {
      return Status(out.status().code(), std::string(corruption::to_string(type)) + " severity " +
                                             std::to_string(severity) + ": " +
                                             out.status().message());
    }
    corrupted = std::move(*out);
  }
  const int height = std::max(
      1, static_cast<int>(std::lround(double(options.thumb_width) * frame.rows / frame.cols)));
  cv::Mat tile;
  cv::resize(corrupted, tile, cv::Size(options.thumb_width, height), 0, 0, cv::INTER_AREA);
  return tile;
}

Result<cv::Mat> gallery_strip(const cv::Mat& frame, Corruption type,
                              const std::vector<int>& severities,
                              const std::vector<std::string>& labels,
                              const GalleryOptions& options) {
  if (severities.empty())
    return Status(StatusCode::kInvalidArgument, "gallery strip: no severities");
  std::vector<cv::Mat> tiles;
  for (std::size_t i = 0; i < severities.size(); ++i) {
    auto tile = gallery_tile(frame, type, severities[i], options);
    if (!tile) return tile.status();
    draw_label(*tile, i < labels.size() ? labels[i] : std::string());
    tiles.push_back(std::move(*tile));
  }
  const int n = static_cast<int>(tiles.size());
  const int w = tiles[0].cols, h = tiles[0].rows;
  cv::Mat strip(h, n * w + (n - 1) * kGapPx, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int i = 0; i < n; ++i)
    tiles[static_cast<std::size_t>(i)].copyTo(strip(cv::Rect(i * (w + kGapPx), 0, w, h)));
  return strip;
}

Result<std::vector<GalleryEntry>> write_gallery(const std::string& out_dir, const cv::Mat& frame,
                                                const GalleryOptions& options,
                                                const GalleryProgress& progress) {
  if (Status s = validate(options); !s) return s;
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir)) {
    return Status(StatusCode::kIoError, "gallery directory '" + out_dir + "': cannot create it" +
                                            (ec ? ": " + ec.message() : std::string()));
  }
  const std::vector<Corruption> types = types_of(options);
  std::vector<GalleryEntry> entries;
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (progress) progress(i, types.size(), types[i]);
    auto strip =
        gallery_strip(frame, types[i], {0, 1, 2, 3, 4, 5}, {"0", "1", "2", "3", "4", "5"}, options);
    if (!strip) return strip.status();
    auto jpeg = codec::encode_jpeg(*strip, options.jpeg_quality);
    if (!jpeg) return jpeg.status();
    GalleryEntry e;
    e.type = types[i];
    e.file = std::string(corruption::to_string(types[i])) + ".jpg";
    e.size = strip->size();
    e.size_bytes = jpeg->size();
    if (Status s = write_bytes(fs::path(out_dir) / e.file, *jpeg); !s) return s;
    entries.push_back(e);
  }
  std::string md = gallery_markdown(entries, options);
  if (Status s = write_bytes(fs::path(out_dir) / "index.md", {md.begin(), md.end()}); !s) return s;
  return entries;
}

std::string gallery_markdown(const std::vector<GalleryEntry>& entries,
                             const GalleryOptions& options, const std::string& link_prefix) {
  std::string md;
  md += "Each picture: " + options.frame_label + ", then severities 1 to 5 (labels 0-5), each ";
  md += "corrupted at full size with a fresh `" + std::string(corruption::to_string(options.rng)) +
        "` RNG seeded " + std::to_string(options.seed) + " and scaled to " +
        std::to_string(options.thumb_width) + " px wide; rolling_shutter turns at " +
        fmt_g(options.yaw_rate_deg_s) + " deg/s.";
  if (!options.command.empty()) md += " Made by `" + options.command + "`.";
  md += "\n\n| name | from | class |\n|---|---|---|\n";
  for (const auto& e : entries) {
    md += std::string("| ") + corruption::to_string(e.type) + " | " + corruption::origin(e.type) +
          " | " + class_text(e.type) + " |\n";
  }
  for (const auto& e : entries) {
    const std::string name = corruption::to_string(e.type);
    md += "\n**" + name + "**: " + parameters_line(e.type) + "\n\n![" + name +
          ": the frame, then severities 1-5](" + link_prefix + e.file + ")\n";
  }
  return md;
}

std::vector<CorruptionThumbnail> corruption_thumbnails(
    const std::vector<ThumbnailRequest>& requests, const std::vector<std::string>& levels,
    const cv::Mat& frame, const GalleryOptions& options) {
  std::vector<CorruptionThumbnail> out;
  for (const auto& r : requests) out.push_back(thumbnail(r, levels, frame, options));
  return out;
}

std::string base64(const std::vector<std::uint8_t>& bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t v = std::uint32_t(bytes[i]) << 16;
    if (n > 1) v |= std::uint32_t(bytes[i + 1]) << 8;
    if (n > 2) v |= bytes[i + 2];
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += n > 1 ? kAlphabet[(v >> 6) & 63] : '=';
    out += n > 2 ? kAlphabet[v & 63] : '=';
  }
  return out;
}

}  // namespace faultline::report
