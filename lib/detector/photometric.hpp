// Exposure and contrast normalisation before colour segmentation. The colour LUT decides by the
// direction of a pixel's BGR vector, so anything that adds light to every channel (fog, snow's
// whitening) or scales it down and adds noise (low light) moves pixels out of their class cone.
// This step undoes what a camera pipeline can estimate from the frame itself, and nothing more:
//   - black level: the dark channel prior (He et al. 2009). Haze adds airlight to every channel, so
//   the darkest
//     channel of the darkest pixels rises with it; subtracting it restores the colour directions.
//     Like the prior itself, this assumes the scene has some dark pixels (shadows, tyres, a
//     colourful object's empty channel); in a frame without any it takes the darkest surface for
//     haze and over-corrects.
//   - white level: the 98th percentile of the brightest channel is stretched to `white_level` (the
//   gain is capped,
//     since it amplifies noise as well).
//   - noise: estimated from the frame (Immerkaer 1996); when the stretch would amplify it past
//   `noise_limit`, the frame
//     is averaged 2x2 first, trading resolution (small, far objects) for colour accuracy.
//   - clipping: a pixel with a channel at `clip_level` or above is over-exposed; its colour carries
//   no reliable
//     shading, so it is blacked out (and thus never classified).
// What cannot be recovered is not guessed: a tone curve (low light's gamma), spatially varying haze
// and noise beyond the 2x2 average degrade the detector, in proportion to how strong they are.
#pragma once

#include <opencv2/core.hpp>

namespace faultline::detector {

struct PhotometricConfig {
  bool enabled = true;
  double white_level = 220;        // target of the 98th-percentile brightest channel
  double max_gain = 6.0;           // stretch limit
  double black_percentile = 0.01;  // of the dark channel (min over B, G, R), taken as the airlight
  double black_fraction = 0.95;    // of that level removed
  double noise_limit =
      6.0;  // per-channel noise sigma after the stretch above which the frame is averaged 2x2
  int clip_level = 253;  // a channel at or above this is over-exposed
};

struct PhotometricStats {
  double black = 0;             // subtracted level
  double white = 0;             // 98th percentile of the brightest channel, before the stretch
  double gain = 1;              // applied stretch
  double noise_sigma = 0;       // estimated per-channel noise sigma of the input
  int bin = 1;                  // 1 or 2: averaging factor applied before the stretch
  double clipped_fraction = 0;  // of pixels blacked out as over-exposed
};

// CV_8UC3 BGR in, CV_8UC3 BGR out: the same size, or half of it (rounded down) when the frame was
// averaged 2x2. The result is `bgr` itself when nothing needs changing, else written into
// `*scratch` when given (its buffer is reused from frame to frame: a fresh 4 MB image per frame
// costs more in page faults than the normalisation itself).
cv::Mat normalise_photometric(const cv::Mat& bgr, const PhotometricConfig& config,
                              PhotometricStats* stats = nullptr, cv::Mat* scratch = nullptr);

// The per-channel noise sigma of a BGR frame, from the median absolute Laplacian-like response of
// Immerkaer's mask on a sparse grid (robust to edges and to sparse speckle).
double estimate_noise_sigma(const cv::Mat& bgr);

}  // namespace faultline::detector
