#include "methods/pathtrace/contribution_roulette.h"

#include <algorithm>

namespace lucent {
namespace {

// The neighbourhood a pixel's value is averaged over: this many pixels each side.
constexpr int kNeighbourhood = 2;
// The mean's lattice: every kLattice-th pixel of every kLattice-th row.
constexpr int kLattice = 4;
// relMSE's floor (lucent compare: (x - r)^2 / (r + 0.01)^2).
constexpr float kRelMseFloor = 0.01f;
// K: how much more likely than under throughput roulette a path of a pixel of the image's mean value
// is to go on. Measured (src/methods/pathtrace/README.md): relMSE x seconds is flat from 2 to 3 on
// the Cornell box and Sponza, 1 is 4% worse.
constexpr float kAim = 2.0f;

float meanOfChannels(const Image& image, int x, int y) {
  return (image.at(x, y, 0) + image.at(x, y, 1) + image.at(x, y, 2)) / 3.0f;
}

bool onLattice(int x, int y) { return x % kLattice == 0 && y % kLattice == 0; }

}  // namespace

RouletteScales::RouletteScales(const Image& pilotMeans, const PixelRect& region)
    : region_(region), imageWidth_(pilotMeans.width()), scale_(region.pixelCount()) {
  const int width = pilotMeans.width(), height = pilotMeans.height();
  double sum = 0;
  uint64_t count = 0;
  for (int y = 0; y < height; y += kLattice)
    for (int x = 0; x < width; x += kLattice) sum += meanOfChannels(pilotMeans, x, y), ++count;
  const float mean = float(sum / double(count));
  // A pilot that met no light says nothing about where light is: throughput roulette.
  if (!(mean > 0)) {
    std::fill(scale_.begin(), scale_.end(), Rgb(1.0f));
    return;
  }
  const float k = kAim * mean;
  for (int y = region.y0; y < region.y1; ++y)
    for (int x = region.x0; x < region.x1; ++x) {
      Rgb value;
      int n = 0;
      for (int ny = std::max(0, y - kNeighbourhood); ny <= std::min(height - 1, y + kNeighbourhood); ++ny)
        for (int nx = std::max(0, x - kNeighbourhood); nx <= std::min(width - 1, x + kNeighbourhood); ++nx, ++n)
          value += Rgb(pilotMeans.at(nx, ny, 0), pilotMeans.at(nx, ny, 1), pilotMeans.at(nx, ny, 2));
      value *= 1.0f / float(n);
      scale_[size_t(y - region.y0) * size_t(region.width()) + size_t(x - region.x0)] =
          Rgb(k / (value.r + kRelMseFloor), k / (value.g + kRelMseFloor), k / (value.b + kRelMseFloor));
    }
}

std::vector<uint32_t> pilotPixels(int width, int height, const PixelRect& region) {
  std::vector<uint32_t> samples(size_t(width) * size_t(height), 0);
  const PixelRect around{std::max(0, region.x0 - kNeighbourhood), std::max(0, region.y0 - kNeighbourhood),
                         std::min(width, region.x1 + kNeighbourhood), std::min(height, region.y1 + kNeighbourhood)};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (around.contains(x, y) || onLattice(x, y)) samples[size_t(y) * size_t(width) + size_t(x)] = kPilotSamples;
  return samples;
}

}  // namespace lucent
