// Contribution roulette (--roulette contribution): Russian roulette by what a path is expected to
// add to its pixel's relative error, not by its throughput alone; and the choice of light learnt
// from its pilot (--light-choice learned, LightMoments below).
//
// A path at a vertex is expected to bring its throughput beta times the radiance L arriving there.
// Ending it with probability 1 - q adds (1/q - 1) E[(beta L)^2] to its pixel's variance and saves
// (1 - q) times the cost of going on; relMSE weighs a pixel's variance by 1 / (I + 0.01)^2 (I its
// value, 0.01 the metric's floor), so the product of the image's error and its time is smallest with
// q proportional to beta L / (I + 0.01). With L taken as the scene's typical radiance, the image's
// mean M: q = min(1, K beta M / (I + 0.01)), per colour channel, the largest. Dark pixels' paths
// go on, bright pixels' end early; throughput roulette is q = min(1, beta), the same for all.
//
// I and M come from a pilot: each pixel's first kPilotSamples samples (taken with throughput
// roulette, and part of the image), I averaged over the pixel's 5 x 5 neighbourhood so that a noisy
// pilot does not decide alone, M over every fourth pixel of every fourth row of the whole image.
// Both depend only on those samples, so a crop, a sample range or a resumed render, which traces the
// pilot's pixels again (pilotPixels), continues with the same q as the whole render: the image stays
// the same for any split. The image is unbiased for any q > 0.
#pragma once
#include <cstdint>
#include <vector>

#include "lucent/core/distribution.h"
#include "lucent/core/exact_sum.h"
#include "lucent/core/math.h"
#include "lucent/image/image.h"
#include "lucent/pipeline/pixel_rect.h"
#include "lucent/scene/scene.h"

namespace lucent {

// The pilot's samples per pixel: the samples before contribution roulette starts.
inline constexpr uint32_t kPilotSamples = 8;

// Per pixel of a region, the scale K M / (I + 0.01) that multiplies a path's throughput in the
// roulette (survivesRussianRoulette); empty: throughput roulette.
class RouletteScales {
 public:
  RouletteScales() = default;
  // From the pilot's pixel means over the whole image (width x height, R, G, B first; only the pixels
  // pilotPixels names are read), for the pixels of `region`.
  RouletteScales(const Image& pilotMeans, const PixelRect& region);
  bool empty() const { return scale_.empty(); }
  // The scale of an image pixel (y * width + x) inside the region.
  Rgb at(uint64_t pixel) const {
    const uint64_t x = pixel % uint64_t(imageWidth_), y = pixel / uint64_t(imageWidth_);
    return scale_[(y - uint64_t(region_.y0)) * uint64_t(region_.width()) + (x - uint64_t(region_.x0))];
  }

 private:
  PixelRect region_;
  int imageWidth_ = 0;
  std::vector<Rgb> scale_;
};

// The pixels whose pilot the scales of `region` read, as samples per pixel of the whole image
// (kPilotSamples or 0): the region and two pixels around it, and the mean's lattice.
std::vector<uint32_t> pilotPixels(int width, int height, const PixelRect& region);

// The choice of light learnt from the same pilot (--light-choice learned). Next-event estimation
// chooses a light by its power, which is right where every light is seen alike; Sponza's sky,
// seen from the galleries through the courtyard's opening, takes 14% of its samples and brings
// less than BSDF sampling finds of it, while the sun's samples carry the galleries' bounced light.
// The variance of a choice among groups of lights is smallest with each group chosen in proportion
// to the square root of the second moment of what its samples bring, f^2 / q: per group (emitting
// triangles; the environment; point, spot and directional lights together), the pilot's lattice
// pixels add each unoccluded light sample's contribution squared, whose mean times the group's
// probability under the pilot's choice estimates it. Within a group lights keep their power's
// shares; a tenth of each group's probability stays its power's, so that a group the pilot did not
// see keeps samples. Sums are exact, so the choice does not depend on threads or tiles.
class LightMoments {
 public:
  // An unoccluded light sample's contribution (the mean of R, G, B: what it brings, divided by the
  // probability of its light and point) from a light of `type`.
  void add(LightType type, Rgb contribution);
  void add(const LightMoments& other);

 private:
  friend Distribution1D learntLightChoice(const Scene& scene, const LightMoments& moments);
  static constexpr int kGroups = 3;
  ExactSum squares_[kGroups];
};

// Whether the path tracer learns the scene's light choice: lights of two or more groups, and no
// nearby lights (chooseLight weighs those by distance).
bool learnsLightChoice(const Scene& scene);
Distribution1D learntLightChoice(const Scene& scene, const LightMoments& moments);

// Whether a pixel is on the pilot's lattice (its light samples teach the light choice).
bool onPilotLattice(int x, int y);

}  // namespace lucent
