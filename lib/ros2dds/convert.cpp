#include "ros2dds/convert.hpp"

#include <algorithm>
#include <cctype>

#include "codec/raw.hpp"

namespace faultline::ros2dds {
namespace {

bool ends_with(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

std::string parent_of(const std::string& topic) {
  const auto slash = topic.rfind('/');
  return slash == std::string::npos || slash == 0 ? std::string() : topic.substr(0, slash);
}

// The topic without image_transport's transport suffix and the image's own name.
std::string image_namespace(const std::string& topic) {
  std::string base = topic;
  if (ends_with(base, "/compressed")) base = parent_of(base);
  return parent_of(base);
}

}  // namespace

RosTime time_from_ns(StampNs stamp_ns) {
  StampNs sec = stamp_ns / kNsPerSec;
  StampNs rem = stamp_ns % kNsPerSec;
  if (rem < 0) {
    rem += kNsPerSec;
    --sec;
  }
  return {static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(rem)};
}

RosTime time_from_us(std::int64_t stamp_us) { return time_from_ns(stamp_us * 1000); }

StampNs ns_from_time(const RosTime& time) {
  return static_cast<StampNs>(time.sec) * kNsPerSec + static_cast<StampNs>(time.nanosec);
}

Result<std::string> dds_topic_name(const std::string& ros_topic) {
  auto bad = [&](const char* why) {
    return Result<std::string>(StatusCode::kInvalidArgument,
                               "ROS topic '" + ros_topic + "': " + why);
  };
  if (ros_topic.size() < 2 || ros_topic.front() != '/')
    return bad("expected an absolute name such as /camera/image_raw");
  if (ros_topic.back() == '/') return bad("ends with '/'");
  if (ros_topic.find("//") != std::string::npos) return bad("contains '//'");
  for (char c : ros_topic) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/')) {
      return bad("only letters, digits, '_' and '/' are allowed");
    }
  }
  return "rt" + ros_topic;
}

std::string ros_type_name(const std::string& dds_type_name) {
  // pkg::msg::dds_::Type_ -> pkg/msg/Type
  const std::string marker = "::dds_::";
  const auto at = dds_type_name.find(marker);
  if (at == std::string::npos || !ends_with(dds_type_name, "_")) return dds_type_name;
  std::string head = dds_type_name.substr(0, at);
  std::string type = dds_type_name.substr(at + marker.size());
  type.pop_back();
  std::string out;
  for (std::size_t i = 0; i < head.size(); ++i) {
    if (head.compare(i, 2, "::") == 0) {
      out += '/';
      ++i;
    } else {
      out += head[i];
    }
  }
  return out + "/" + type;
}

std::optional<ImageType> image_type_of(const std::string& dds_type_name) {
  if (dds_type_name == kCompressedImageType) return ImageType::kCompressed;
  if (dds_type_name == kImageType) return ImageType::kRaw;
  return std::nullopt;
}

bool is_supported_encoding(std::string_view encoding) { return codec::is_raw_encoding(encoding); }

Result<cv::Mat> raw_to_bgr(const RawImageView& image) {
  return codec::raw_to_bgr(image.encoding, image.width, image.height, image.step, image.data,
                           image.size_bytes);
}

CameraInfoValues camera_info_from_intrinsics(const std::vector<double>& k, std::uint32_t width,
                                             std::uint32_t height) {
  CameraInfoValues c;
  c.width = width;
  c.height = height;
  c.d.assign(5, 0.0);
  c.r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (k.size() == 9) {
    std::copy(k.begin(), k.end(), c.k.begin());
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col)
        c.p[static_cast<std::size_t>(row * 4 + col)] = k[static_cast<std::size_t>(row * 3 + col)];
    }
  }
  return c;
}

std::string camera_info_topic(const std::string& image_topic) {
  return image_namespace(image_topic) + "/camera_info";
}

std::string channel_from_topic(const std::string& image_topic) {
  std::string ns = image_namespace(image_topic);
  if (ns.empty()) ns = image_topic;
  std::string out;
  for (char c : ns) {
    if (c == '/') {
      if (!out.empty()) out += '_';
    } else {
      out += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
  }
  return out;
}

}  // namespace faultline::ros2dds
