#include "bench/frames.hpp"

#include <opencv2/imgproc.hpp>

#include "codec/jpeg.hpp"
#include "dataset/synth_frame.hpp"
#include "rng/fast_rng.hpp"

namespace faultline::bench {

// Moved to lib/dataset so the product (gallery, report thumbnails) shows the same frame.
cv::Mat realistic_frame(int width, int height, std::uint64_t seed) {
  return dataset::realistic_frame(width, height, seed);
}

const char* to_string(FrameKind kind) { return kind == FrameKind::kNoisy ? "noisy" : "realistic"; }

std::optional<FrameKind> frame_kind_from_string(const std::string& name) {
  if (name == "realistic") return FrameKind::kRealistic;
  if (name == "noisy") return FrameKind::kNoisy;
  return std::nullopt;
}

cv::Mat bench_pixels(const BenchFrame& frame) {
  if (frame.kind == FrameKind::kRealistic)
    return realistic_frame(frame.width, frame.height, frame.seed);
  FrameSpec spec;
  spec.width = frame.width;
  spec.height = frame.height;
  spec.seed = frame.seed;
  spec.noise = frame.noisy_noise;
  return synthetic_frame(spec);
}

Result<std::vector<std::uint8_t>> bench_jpeg(const BenchFrame& frame) {
  const int quality = frame.kind == FrameKind::kRealistic ? kRealisticQuality : frame.noisy_quality;
  if (frame.width < 16 || frame.height < 16 || quality < 1 || quality > 100) {
    return Status(StatusCode::kInvalidArgument, "bench frame: " + std::to_string(frame.width) +
                                                    "x" + std::to_string(frame.height) +
                                                    " at quality " + std::to_string(quality) +
                                                    ": expected >= 16x16 and 1..100");
  }
  return codec::encode_jpeg(bench_pixels(frame), quality);
}

cv::Mat synthetic_frame(const FrameSpec& spec) {
  const int width = spec.width, height = spec.height;
  cv::Mat img(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    auto* row = img.ptr<cv::Vec3b>(y);
    for (int x = 0; x < width; ++x) {
      const double t = static_cast<double>(y) / height;
      row[x] = cv::Vec3b(static_cast<uchar>(230 - 80 * t), static_cast<uchar>(200 - 60 * t),
                         static_cast<uchar>(150 + 40 * t * (x % 400) / 400.0));
    }
  }
  rng::FastRng rng(spec.seed);
  for (int b = 0; b < 14; ++b) {
    const int x0 = b * width / 14, w = width / 14 - 8;
    const int h = 150 + static_cast<int>(rng.next_u32() % 250);
    // Drawn last channel first, in named steps: the order of a call's argument evaluation is
    // unspecified (gcc, which made the frames the figures were measured on, went right to left;
    // clang goes left to right).
    const double red = 60 + rng.next_u32() % 120, green = 60 + rng.next_u32() % 120,
                 blue = 60 + rng.next_u32() % 120;
    const cv::Scalar c(blue, green, red);
    cv::rectangle(img, cv::Rect(x0, height / 2 - h, w, h), c, cv::FILLED);
    for (int wy = height / 2 - h + 10; wy < height / 2 - 20; wy += 30) {
      for (int wx = x0 + 8; wx < x0 + w - 16; wx += 24) {
        cv::rectangle(img, cv::Rect(wx, wy, 12, 16), cv::Scalar(40, 200, 240), cv::FILLED);
      }
    }
  }
  cv::rectangle(img, cv::Rect(0, height / 2, width, height / 2), cv::Scalar(70, 72, 75),
                cv::FILLED);
  for (int i = 0; i < 8; ++i) {
    cv::line(img, cv::Point(width / 2 + (i - 4) * 40, height / 2),
             cv::Point(width / 2 + (i - 4) * 260, height), cv::Scalar(235, 235, 235), 6,
             cv::LINE_AA);
  }
  cv::circle(img, cv::Point(width / 3, height * 3 / 4), 60, cv::Scalar(20, 20, 200), cv::FILLED,
             cv::LINE_AA);
  cv::putText(img, "FAULTLINE 1600x900", cv::Point(80, 120), cv::FONT_HERSHEY_SIMPLEX, 3.0,
              cv::Scalar(255, 0, 255), 6, cv::LINE_AA);
  // Noise as a saturating add of [0, 2 noise] and a subtract of noise (the bytes `bench corrupt`
  // has always used).
  const auto span = static_cast<std::uint32_t>(2 * spec.noise + 1);
  cv::Mat noise(img.size(), CV_8UC3);
  for (int y = 0; y < height; ++y) {
    auto* p = noise.ptr<uchar>(y);
    for (int x = 0; x < width * 3; ++x) p[x] = static_cast<uchar>(rng.next_u32() % span);
  }
  cv::add(img, noise, img);
  cv::subtract(img, cv::Scalar::all(spec.noise), img);
  return img;
}

}  // namespace faultline::bench
