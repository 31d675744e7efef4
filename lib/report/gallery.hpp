// Pictures of the corruptions, for people: the fault catalogue's strips (`faultline corrupt
// --gallery`, docs/faults/) and the benchmark report's thumbnails. Every tile is the frame
// corrupted at full size with a fresh RNG of the given seed (exactly what `faultline corrupt
// --seed S` writes), then scaled down, so the pictures show what the faults do to a real-sized
// frame. Pure apart from write_gallery, which writes files.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/status.hpp"
#include "corruption/types.hpp"

namespace faultline::report {

// rolling_shutter needs ego motion: the gallery turns at 60 deg/s, a tight urban turn (a 90°
// corner in 1.5 s), so the lean is visible on a thumbnail (severity 5 shifts the top and bottom
// rows of a 1600-wide frame about 66 px apart).
inline constexpr double kGalleryYawRateDegS = 60.0;
// The built-in frame: the synthetic dataset's front camera at nuScenes' 1600 x 900.
inline constexpr int kGalleryFrameWidth = 1600;
inline constexpr int kGalleryFrameHeight = 900;
inline constexpr std::uint64_t kGalleryFrameSeed = 0;  // scene 0, front camera

struct GalleryOptions {
  std::vector<corruption::Corruption> types;  // empty = every corruption, kAllCorruptions order
  std::uint32_t seed = 0;                     // each tile's RNG seed (as `corrupt --seed`)
  corruption::RngMode rng = corruption::RngMode::Fast;
  int thumb_width = 224;  // pixels per tile, 16..1600; the height keeps the frame's aspect
  int jpeg_quality = 80;  // of the written JPEGs, 1..100 (TurboJPEG, 4:2:0)
  double yaw_rate_deg_s = kGalleryYawRateDegS;  // rolling_shutter's ego yaw rate
  std::string frame_label = "the built-in 1600 x 900 synthetic front-camera frame";  // for index.md
  std::string command;  // the command line that made the gallery, quoted in index.md ("" = none)
};

// kInvalidArgument naming the option for a thumb width or JPEG quality out of range.
Status validate(const GalleryOptions& options);

// The built-in frame (kGalleryFrame*: dataset::realistic_frame), BGR CV_8UC3.
cv::Mat gallery_frame();

// One tile: `frame` (BGR CV_8UC3) corrupted at `severity` (0 = the frame itself), scaled to
// options.thumb_width (INTER_AREA). The corruption's error if it fails.
Result<cv::Mat> gallery_tile(const cv::Mat& frame, corruption::Corruption type, int severity,
                             const GalleryOptions& options);

// The tiles of `severities` side by side, 2 px of white between them, tile i labelled labels[i] in
// its top-left corner (labels may be shorter: the rest unlabelled).
Result<cv::Mat> gallery_strip(const cv::Mat& frame, corruption::Corruption type,
                              const std::vector<int>& severities,
                              const std::vector<std::string>& labels,
                              const GalleryOptions& options);

struct GalleryEntry {
  corruption::Corruption type{};
  std::string file;  // file name in the gallery directory: "<type>.jpg"
  cv::Size size;     // strip size in pixels
  std::size_t size_bytes = 0;
};

// Called before each strip is rendered: index 0..count-1.
using GalleryProgress =
    std::function<void(std::size_t index, std::size_t count, corruption::Corruption type)>;

// Writes <out_dir>/<type>.jpg for every type (the frame, then severities 1..5) and
// <out_dir>/index.md (gallery_markdown with links relative to out_dir); creates out_dir. Errors
// name the file or directory, or the corruption that failed.
Result<std::vector<GalleryEntry>> write_gallery(const std::string& out_dir, const cv::Mat& frame,
                                                const GalleryOptions& options,
                                                const GalleryProgress& progress = {});

// The catalogue in Markdown: a table of every entry's origin and fidelity class, then per entry
// its picture (link_prefix + file) and its parameters at severities 1..5.
std::string gallery_markdown(const std::vector<GalleryEntry>& entries,
                             const GalleryOptions& options, const std::string& link_prefix = "");

// One corruption of a benchmark, for the report's thumbnails.
struct ThumbnailRequest {
  std::string name;  // as the benchmark names it ("low_light", "camera_crash")
  std::string type;  // the image corruption it applies ("dark"); not one = no picture
};

struct CorruptionThumbnail {
  std::string name;                // ThumbnailRequest::name
  std::string caption;             // levels and severities shown, or why there is no picture
  std::vector<std::uint8_t> jpeg;  // the levels' tiles side by side; empty = no picture
  int width = 0, height = 0;       // of the JPEG
};

// One thumbnail per request: the levels ("easy", "mid", "hard") side by side at the corruption's
// severities for them (corruption::severity_for). A request whose type is not an image corruption
// (camera_crash, frame_lost: whole frames go missing) or a level that is not one gets a caption
// saying so and no picture; a corruption that fails gets its error as caption.
std::vector<CorruptionThumbnail> corruption_thumbnails(
    const std::vector<ThumbnailRequest>& requests, const std::vector<std::string>& levels,
    const cv::Mat& frame, const GalleryOptions& options);

// Standard base64 (RFC 4648, with padding), for data: URIs.
std::string base64(const std::vector<std::uint8_t>& bytes);

}  // namespace faultline::report
