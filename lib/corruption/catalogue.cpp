// The catalogue's text: one switch per family, each reading the kernels' own parameter functions.
#include "corruption/catalogue.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>

#include "corruption/brightness.hpp"
#include "corruption/color_quant.hpp"
#include "corruption/dark.hpp"
#include "corruption/defocus_blur.hpp"
#include "corruption/digital.hpp"
#include "corruption/elastic_transform.hpp"
#include "corruption/exposure_flicker.hpp"
#include "corruption/fog.hpp"
#include "corruption/frost.hpp"
#include "corruption/glare.hpp"
#include "corruption/glass_blur.hpp"
#include "corruption/motion_blur.hpp"
#include "corruption/noise.hpp"
#include "corruption/recompression.hpp"
#include "corruption/rolling_shutter.hpp"
#include "corruption/snow.hpp"
#include "corruption/soiling.hpp"
#include "corruption/spatter.hpp"
#include "corruption/transport_corruption.hpp"
#include "corruption/water_drops.hpp"
#include "corruption/zoom_blur.hpp"

namespace faultline::corruption {
namespace {

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...) {
  char buf[256];
  va_list args;
  va_start(args, f);
  std::vsnprintf(buf, sizeof buf, f, args);
  va_end(args);
  return buf;
}

// nuScenes-C's six (spec corruptions.md §2-7); "" for any other corruption.
std::string nuscenes_c_parameters(Corruption c, int s) {
  switch (c) {
    case Corruption::Brightness:
      return fmt("HSV V + %g", brightness_offset(s));
    case Corruption::Dark: {
      const DarkParams p = dark_params(s);
      return fmt("stretch to %g, Poisson scale %g, read noise σ %g", p.target_max, p.poisson_scale,
                 p.sigma);
    }
    case Corruption::Fog: {
      const FogParams p = fog_params(s);
      return fmt("strength %g, plasma decay %g", p.strength, p.decay);
    }
    case Corruption::Snow: {
      const SnowParams p = snow_params(s);
      return fmt("flakes N(%g, %g) > %g zoomed %g x, streak radius %d σ %d, blend %g", p.loc,
                 p.scale, p.threshold, p.zoom, p.radius, p.sigma, p.blend);
    }
    case Corruption::MotionBlur: {
      const MotionBlurParams p = motion_blur_params(s);
      return fmt("streak radius %d, σ %d", p.radius, p.sigma);
    }
    case Corruption::ColorQuant:
      return fmt("%d bits per channel", 5 - std::clamp(s, 1, 5));
    default:
      return "";
  }
}

// imagecorruptions' pointwise and digital ones and RoboBEV's ISONoise.
std::string pointwise_parameters(Corruption c, int s) {
  switch (c) {
    case Corruption::GaussianNoise:
      return fmt("σ %g", gaussian_noise_sigma(s));
    case Corruption::ShotNoise:
      return fmt("%g photons per unit", shot_noise_scale(s));
    case Corruption::ImpulseNoise:
      return fmt("%g %% of values salt or pepper", 100 * impulse_noise_amount(s));
    case Corruption::SpeckleNoise:
      return fmt("σ %g (x relative)", speckle_noise_sigma(s));
    case Corruption::IsoNoise:
      return fmt("Poisson(25x)/25 + N(0, %g)", iso_noise_sigma(s));
    case Corruption::Contrast:
      return fmt("contrast x %g", contrast_factor(s));
    case Corruption::Saturate: {
      const SaturateParams p = saturate_params(s);
      return fmt("HSV S x %g + %g", p.scale, p.offset);
    }
    case Corruption::Pixelate:
      return fmt("BOX down to %g x, NEAREST up", pixelate_factor(s));
    case Corruption::JpegCompression:
      return fmt("JPEG quality %d", jpeg_compression_quality(s));
    case Corruption::GaussianBlur:
      return fmt("σ %g px", gaussian_blur_sigma(s));
    default:
      return "";
  }
}

// imagecorruptions' blur, weather and geometric ones.
std::string spatial_parameters(Corruption c, int s) {
  switch (c) {
    case Corruption::DefocusBlur: {
      const DefocusParams p = defocus_params(s);
      return fmt("disk radius %d px, anti-alias σ %g", p.radius, p.alias_blur);
    }
    case Corruption::GlassBlur: {
      const GlassParams p = glass_params(s);
      return fmt("σ %g, pixel swaps ±%d px, %d passes", p.sigma, p.delta, p.iterations);
    }
    case Corruption::ZoomBlur: {
      const std::vector<double> z = zoom_blur_factors(s);
      return fmt("%zu zooms up to %.2f x", z.size(), z.empty() ? 1.0 : z.back());
    }
    case Corruption::Frost: {
      const FrostParams p = frost_params(s);
      return fmt("image x %g + frost x %g", p.image_weight, p.texture_weight);
    }
    case Corruption::ElasticTransform:
      return fmt("displacement alpha %g", elastic_alpha(s));
    case Corruption::Spatter: {
      const SpatterParams p = spatter_params(s);
      return fmt("%s, field N(%g, %g) σ %g > %g", p.mud ? "mud" : "water", p.loc, p.scale, p.sigma,
                 p.threshold);
    }
    default:
      return "";
  }
}

// Faultline's sensor, stream and system faults.
std::string own_parameters(Corruption c, int s) {
  switch (c) {
    case Corruption::Soiling: {
      const SoilingParams p = soiling_params(s);
      return fmt("%d blobs on %g %%, opacity %g, transmission %g", p.blobs, 100 * p.coverage,
                 p.opacity, p.transmission);
    }
    case Corruption::WaterDrops: {
      const WaterDropsParams p = water_drops_params(s);
      return fmt("%d drops of %g-%g %% of the height, %g new/s", p.drops, 100 * p.min_radius,
                 100 * p.max_radius, p.rain_per_s);
    }
    case Corruption::Glare: {
      const GlareParams p = glare_params(s);
      return fmt("veil %g, bloom %g %% of the diagonal, streaks %g, %d ghosts", p.veil,
                 100 * p.bloom, p.streak, p.ghosts);
    }
    case Corruption::ExposureFlicker: {
      const ExposureFlickerParams p = exposure_flicker_params(s);
      return fmt("flicker ±%g EV, hunting ±%g EV, bands %g %%", p.flicker_ev, p.hunting_ev,
                 100 * p.band_depth);
    }
    case Corruption::TransportCorruption: {
      const TransportParams p = transport_params(s);
      std::string t = fmt("%d bit flips, %d lost packets", p.bit_flips, p.lost_packets);
      if (p.truncate_from < 1.0)
        t += fmt(", cut at %g-%g of the scan", p.truncate_from, p.truncate_to);
      return t;
    }
    case Corruption::Recompression: {
      const RecompressionParams p = recompression_params(s);
      return fmt("quality %d, %d generation%s", p.quality, p.generations,
                 p.generations == 1 ? "" : "s");
    }
    case Corruption::RollingShutter:
      return fmt("readout %g ms", rolling_shutter_readout_ms(s));
    default:
      return "";
  }
}

}  // namespace

const char* to_string(Fidelity f) {
  switch (f) {
    case Fidelity::ReferenceExact:
      return "reference-exact";
    case Fidelity::Statistical:
      return "statistical";
    case Fidelity::Own:
      return "own";
  }
  return "?";
}

Fidelity fidelity(Corruption c) {
  if (c == Corruption::ImpulseNoise) return Fidelity::Statistical;
  return std::string(origin(c)) == "Faultline" ? Fidelity::Own : Fidelity::ReferenceExact;
}

const char* origin(Corruption c) {
  switch (c) {  // no default: a new corruption must say where it comes from
    case Corruption::Brightness:
    case Corruption::Dark:
    case Corruption::Fog:
    case Corruption::Snow:
    case Corruption::MotionBlur:
    case Corruption::ColorQuant:
      return "nuScenes-C";
    case Corruption::IsoNoise:
      return "RoboBEV";
    case Corruption::GaussianNoise:
    case Corruption::ShotNoise:
    case Corruption::ImpulseNoise:
    case Corruption::SpeckleNoise:
    case Corruption::Contrast:
    case Corruption::Saturate:
    case Corruption::Pixelate:
    case Corruption::JpegCompression:
    case Corruption::GaussianBlur:
    case Corruption::DefocusBlur:
    case Corruption::GlassBlur:
    case Corruption::ZoomBlur:
    case Corruption::Frost:
    case Corruption::ElasticTransform:
    case Corruption::Spatter:
      return "imagecorruptions 1.1.2";
    case Corruption::Soiling:
    case Corruption::WaterDrops:
    case Corruption::Glare:
    case Corruption::ExposureFlicker:
    case Corruption::TransportCorruption:
    case Corruption::Recompression:
    case Corruption::RollingShutter:
      return "Faultline";
  }
  return "?";
}

const char* fidelity_note(Corruption c) {
  switch (c) {
    case Corruption::Dark:
    case Corruption::IsoNoise:
      return "severity 5 own: the reference raises IndexError there";
    case Corruption::ImpulseNoise:
      return "skimage's algorithm on the seeded stream: the reference's draws cannot be seeded";
    default:
      return "";
  }
}

std::string severity_parameters(Corruption c, int severity) {
  const int s = std::clamp(severity, 1, 5);
  for (auto* family :
       {&nuscenes_c_parameters, &pointwise_parameters, &spatial_parameters, &own_parameters}) {
    std::string text = family(c, s);
    if (!text.empty()) return text;
  }
  return "";
}

}  // namespace faultline::corruption
