// Connected components of the class-label image: one Blob per same-class region, in full-resolution
// pixels.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "detector/color_lut.hpp"

namespace faultline::detector {

struct Blob {
  int cls = 0;                            // dataset::SynthClass index
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // bounding box, full-resolution pixels (x1, y1 exclusive)
  double area_px = 0;                     // full-resolution pixel count
  bool touches_left = false, touches_right = false, touches_top = false, touches_bottom = false;
  bool bottom_occluded =
      false;  // most of the bottom edge sits on another class (an occluder in front)
  double u_centre() const { return 0.5 * (x0 + x1); }
};

struct BlobConfig {
  double min_area_px = 60;  // full-resolution pixels; scaled with the input scale
  int min_side_px = 3;      // at the processed scale
  double max_gap_px = 4;  // bridge_label_gaps, full-resolution pixels; scaled with the input scale
};

// Fills runs of at most `max_gap` unlabelled pixels between two pixels of the same class, first
// along rows, then along columns. Snow flakes, speckle and JPEG fringes cut one object into
// fragments that each look like a small, distant object; bridging short gaps keeps it whole without
// merging objects of different classes.
void bridge_label_gaps(cv::Mat& labels, int max_gap);

// `labels` is a CV_8UC1 class-label image at `scale` of the full `full_width` x `full_height`
// image. One 8-connected labelling pass over all classes at once; blobs ordered by class, then in
// the order cv::connectedComponentsWithStats numbers each class's components (first 2x2 block in
// raster order).
std::vector<Blob> find_blobs(const cv::Mat& labels, double scale, const BlobConfig& config = {});

// Reference: one cv::compare + cv::connectedComponentsWithStats pass per class (slow on noisy
// frames, where every class has scattered pixels). find_blobs returns exactly the same blobs; kept
// for the tests.
std::vector<Blob> find_blobs_per_class(const cv::Mat& labels, double scale,
                                       const BlobConfig& config = {});

}  // namespace faultline::detector
