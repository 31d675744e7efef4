#include "fake_detector.hpp"

#include "detection.pb.h"
#include "transport/publisher.hpp"
#include "transport/subscriber.hpp"
#include "transport/typed.hpp"

namespace faultline::runtime::testing {

struct FakeDetector::Impl {
  transport::RawSubscriber sub;
  transport::Publisher push;
  Impl(const std::string& input, const std::string& sink, int hwm)
      : sub([&] {
          transport::SubscriberConfig c;
          c.endpoints = {input};
          c.topics = {"/faulty/", "/sync/sample"};
          c.rcv_hwm = hwm;
          return c;
        }()),
        push([&] {
          transport::PublisherConfig c;
          c.endpoint = sink;
          c.bind = false;
          c.pattern = transport::Pattern::PushPull;
          c.linger_ms = 500;
          return c;
        }()) {}
};

FakeDetector::FakeDetector(const std::string& input_endpoint, const std::string& sink_endpoint,
                           int hwm)
    : impl_(new Impl(input_endpoint, sink_endpoint, hwm)) {}

FakeDetector::~FakeDetector() { delete impl_; }

FakeDetectorResult FakeDetector::run(const std::atomic<bool>& stop) {
  FakeDetectorResult out;
  transport::DropCounter drops;
  std::uint64_t seq = 0;
  while (!stop.load() && !out.saw_last) {
    auto r = impl_->sub.receive(50 * kNsPerMs);
    if (!r.is_ok()) continue;
    const std::string topic(r->topic());
    if (topic == "/sync/sample") {
      msgs::SampleBoundary b;
      if (!transport::parse_message(*r, &b).is_ok()) {
        ++out.malformed;
        continue;
      }
      ++out.boundaries;
      msgs::DetectionArray d;
      d.set_sample_token(b.sample_token());
      d.set_detector("fake_detector");
      d.mutable_header()->set_seq(++seq);
      d.mutable_header()->set_publisher("fake_detector");
      d.mutable_header()->set_publish_mono_ns(monotonic_now_ns());
      auto* box = d.add_detections();
      for (double v : {10.0, 20.0, 1.0}) box->add_translation(v);
      for (double v : {1.9, 4.5, 1.6}) box->add_size(v);
      for (double v : {1.0, 0.0, 0.0, 0.0}) box->add_rotation(v);
      for (double v : {0.0, 0.0}) box->add_velocity(v);
      box->set_detection_name("car");
      box->set_detection_score(0.9);
      box->set_attribute_name("vehicle.moving");
      (void)transport::send_message(impl_->push, "/detections", d);
      out.saw_last = b.last_in_run();
      continue;
    }
    auto view = transport::parse_camera_frame(*r);
    if (!view) {
      ++out.malformed;
      continue;
    }
    drops.observe(view->header.header().publisher(), topic, view->header.header().seq());
    ++out.frames;
    ++out.frames_per_topic[topic];
  }
  out.transport_drops = drops.total().transport_drops;
  return out;
}

}  // namespace faultline::runtime::testing
