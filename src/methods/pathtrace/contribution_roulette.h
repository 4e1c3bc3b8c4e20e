// Contribution roulette (--roulette contribution): Russian roulette by what a path is expected to
// add to its pixel's relative error, not by its throughput alone.
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

#include "lucent/core/math.h"
#include "lucent/image/image.h"
#include "lucent/pipeline/pixel_rect.h"

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

}  // namespace lucent
