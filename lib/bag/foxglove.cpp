// Faultline -> Foxglove message conversion.
#include "bag/foxglove.hpp"

#include <cctype>

#include "deterministic_serialize.hpp"

namespace faultline::bag {

std::string camera_frame_id(std::string_view camera) {
  std::string out(camera);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string image_topic(std::string_view camera) {
  return "/" + camera_frame_id(camera) + "/image_rect_compressed";
}

std::string camera_info_topic(std::string_view camera) {
  return "/" + camera_frame_id(camera) + "/camera_info";
}

void set_timestamp(StampNs stamp_ns, google::protobuf::Timestamp* out) {
  StampNs sec = stamp_ns / 1'000'000'000;
  StampNs nsec = stamp_ns % 1'000'000'000;
  if (nsec < 0) {  // Timestamp wants nanos in [0, 1e9)
    nsec += 1'000'000'000;
    sec -= 1;
  }
  out->set_seconds(sec);
  out->set_nanos(static_cast<std::int32_t>(nsec));
}

foxglove::CompressedImage to_compressed_image(const msgs::CameraFrame& frame,
                                              std::string_view jpeg) {
  foxglove::CompressedImage img;
  set_timestamp(frame.header().capture_stamp_ns(), img.mutable_timestamp());
  img.set_frame_id(camera_frame_id(frame.camera()));
  img.set_data(jpeg.data(), jpeg.size());
  img.set_format(frame.encoding().empty() ? "jpeg" : frame.encoding());
  return img;
}

foxglove::RawImage to_raw_image(const msgs::CameraFrame& frame, std::string_view pixels) {
  foxglove::RawImage img;
  set_timestamp(frame.header().capture_stamp_ns(), img.mutable_timestamp());
  img.set_frame_id(camera_frame_id(frame.camera()));
  img.set_width(frame.width());
  img.set_height(frame.height());
  img.set_encoding(frame.encoding());
  img.set_step(frame.step());
  img.set_data(pixels.data(), pixels.size());
  return img;
}

namespace {
// Appends the tag (field, wire type 2) and the varint length of a bytes field.
void append_bytes_field_prefix(int field, std::size_t size, std::string& out) {
  out.push_back(static_cast<char>((field << 3) | 2));
  auto v = static_cast<std::uint64_t>(size);
  while (v >= 0x80) {
    out.push_back(static_cast<char>((v & 0x7f) | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<char>(v));
}
}  // namespace

void compressed_image_head(const msgs::CameraFrame& frame, std::size_t image_bytes,
                           std::string& head) {
  foxglove::CompressedImage img = to_compressed_image(frame, std::string_view("", 0));
  msgs::serialize_deterministic(img, &head);
  append_bytes_field_prefix(foxglove::CompressedImage::kDataFieldNumber, image_bytes, head);
}

void raw_image_head(const msgs::CameraFrame& frame, std::size_t image_bytes, std::string& head) {
  foxglove::RawImage img = to_raw_image(frame, std::string_view("", 0));
  msgs::serialize_deterministic(img, &head);
  append_bytes_field_prefix(foxglove::RawImage::kDataFieldNumber, image_bytes, head);
}

foxglove::CameraCalibration to_camera_calibration(const msgs::CameraFrame& frame) {
  foxglove::CameraCalibration cal;
  set_timestamp(frame.header().capture_stamp_ns(), cal.mutable_timestamp());
  cal.set_frame_id(camera_frame_id(frame.camera()));
  cal.set_width(frame.width());
  cal.set_height(frame.height());
  cal.set_distortion_model("");
  std::array<double, 9> k{};
  for (int i = 0; i < 9 && i < frame.intrinsics_size(); ++i)
    k[static_cast<std::size_t>(i)] = frame.intrinsics(i);
  for (double v : k) cal.add_k(v);
  for (int i = 0; i < 9; ++i) cal.add_r(i % 4 == 0 ? 1.0 : 0.0);
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 4; ++col) {
      cal.add_p(col < 3 ? k[static_cast<std::size_t>(row * 3 + col)] : 0.0);
    }
  }
  return cal;
}

namespace {
void set_transform(const msgs::Transform& t, foxglove::FrameTransform& out) {
  out.mutable_translation()->set_x(t.translation().x());
  out.mutable_translation()->set_y(t.translation().y());
  out.mutable_translation()->set_z(t.translation().z());
  out.mutable_rotation()->set_x(t.rotation().x());
  out.mutable_rotation()->set_y(t.rotation().y());
  out.mutable_rotation()->set_z(t.rotation().z());
  out.mutable_rotation()->set_w(t.rotation().w());
}

void set_box(const std::array<double, 3>& translation, const std::array<double, 3>& size_wlh,
             const std::array<double, 4>& rotation_wxyz, const std::array<double, 4>& rgba,
             foxglove::SceneEntity& entity) {
  foxglove::CubePrimitive* cube = entity.add_cubes();
  auto* pose = cube->mutable_pose();
  pose->mutable_position()->set_x(translation[0]);
  pose->mutable_position()->set_y(translation[1]);
  pose->mutable_position()->set_z(translation[2]);
  pose->mutable_orientation()->set_w(rotation_wxyz[0]);
  pose->mutable_orientation()->set_x(rotation_wxyz[1]);
  pose->mutable_orientation()->set_y(rotation_wxyz[2]);
  pose->mutable_orientation()->set_z(rotation_wxyz[3]);
  cube->mutable_size()->set_x(size_wlh[1]);  // length along the box's x axis
  cube->mutable_size()->set_y(size_wlh[0]);
  cube->mutable_size()->set_z(size_wlh[2]);
  cube->mutable_color()->set_r(rgba[0]);
  cube->mutable_color()->set_g(rgba[1]);
  cube->mutable_color()->set_b(rgba[2]);
  cube->mutable_color()->set_a(rgba[3]);
}

foxglove::SceneEntity* new_entity(foxglove::SceneUpdate& update, StampNs stamp_ns, std::string id,
                                  const std::string& category) {
  foxglove::SceneEntity* e = update.add_entities();
  set_timestamp(stamp_ns, e->mutable_timestamp());
  e->set_frame_id("map");
  e->set_id(std::move(id));
  e->set_frame_locked(true);
  auto* kv = e->add_metadata();
  kv->set_key("category");
  kv->set_value(category);
  return e;
}

void delete_all(foxglove::SceneUpdate& update, StampNs stamp_ns) {
  auto* del = update.add_deletions();
  set_timestamp(stamp_ns, del->mutable_timestamp());
  del->set_type(foxglove::SceneEntityDeletion::ALL);
}

std::array<double, 3> to3(const google::protobuf::RepeatedField<double>& v) {
  std::array<double, 3> out{};
  for (int i = 0; i < 3 && i < v.size(); ++i) out[static_cast<std::size_t>(i)] = v.Get(i);
  return out;
}
}  // namespace

foxglove::FrameTransform ego_transform(const msgs::CameraFrame& frame) {
  foxglove::FrameTransform tf;
  set_timestamp(frame.header().capture_stamp_ns(), tf.mutable_timestamp());
  tf.set_parent_frame_id("map");
  tf.set_child_frame_id("base_link");
  set_transform(frame.ego_pose(), tf);
  return tf;
}

foxglove::FrameTransform sensor_transform(const msgs::CameraFrame& frame) {
  foxglove::FrameTransform tf;
  set_timestamp(frame.header().capture_stamp_ns(), tf.mutable_timestamp());
  tf.set_parent_frame_id("base_link");
  tf.set_child_frame_id(camera_frame_id(frame.camera()));
  set_transform(frame.sensor_to_ego(), tf);
  return tf;
}

foxglove::SceneUpdate gt_scene_update(const std::vector<GtBox>& boxes, StampNs stamp_ns) {
  foxglove::SceneUpdate update;
  delete_all(update, stamp_ns);
  for (const GtBox& box : boxes) {
    foxglove::SceneEntity* e =
        new_entity(update, stamp_ns, box.instance_token.substr(0, 4), box.category);
    set_box(box.translation, box.size, box.rotation, {0.0, 0.8, 0.2, 0.5}, *e);
  }
  return update;
}

foxglove::SceneUpdate detection_scene_update(const msgs::DetectionArray& detections,
                                             StampNs stamp_ns) {
  foxglove::SceneUpdate update;
  delete_all(update, stamp_ns);
  for (int i = 0; i < detections.detections_size(); ++i) {
    const msgs::Detection& d = detections.detections(i);
    foxglove::SceneEntity* e =
        new_entity(update, stamp_ns, "det" + std::to_string(i), d.detection_name());
    auto* score = e->add_metadata();
    score->set_key("score");
    score->set_value(std::to_string(d.detection_score()));
    std::array<double, 4> rot{1, 0, 0, 0};
    for (int k = 0; k < 4 && k < d.rotation_size(); ++k)
      rot[static_cast<std::size_t>(k)] = d.rotation(k);
    set_box(to3(d.translation()), to3(d.size()), rot, {0.9, 0.2, 0.1, 0.5}, *e);
  }
  return update;
}

}  // namespace faultline::bag
