#include "methods/pathtrace/contribution_roulette.h"

#include <algorithm>
#include <cmath>
#include <vector>

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

// The group of a light in the learnt light choice.
int lightGroup(LightType type) { return type == LightType::Triangle ? 0 : type == LightType::Environment ? 1 : 2; }

// The share of the light choice that stays by power.
constexpr float kPowerShare = 0.1f;

}  // namespace

bool onPilotLattice(int x, int y) { return x % kLattice == 0 && y % kLattice == 0; }

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
      // A pixel filter's negative lobes (Mitchell's) can make the neighbourhood's mean negative: as
      // dark as a pixel can be, never a scale of zero or less, which would end its paths for certain.
      const auto scaleOf = [&](float v) { return k / (std::max(v, 0.0f) + kRelMseFloor); };
      scale_[size_t(y - region.y0) * size_t(region.width()) + size_t(x - region.x0)] =
          Rgb(scaleOf(value.r), scaleOf(value.g), scaleOf(value.b));
    }
}

std::vector<uint32_t> pilotPixels(int width, int height, const PixelRect& region) {
  std::vector<uint32_t> samples(size_t(width) * size_t(height), 0);
  const PixelRect around{std::max(0, region.x0 - kNeighbourhood), std::max(0, region.y0 - kNeighbourhood),
                         std::min(width, region.x1 + kNeighbourhood), std::min(height, region.y1 + kNeighbourhood)};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (around.contains(x, y) || onPilotLattice(x, y)) samples[size_t(y) * size_t(width) + size_t(x)] = kPilotSamples;
  return samples;
}

void LightMoments::add(LightType type, Rgb contribution) {
  const float c = (contribution.r + contribution.g + contribution.b) / 3.0f;
  if (ExactSum::accepts(c * c)) squares_[lightGroup(type)].add(c * c);
}

void LightMoments::add(const LightMoments& other) {
  for (int g = 0; g < kGroups; ++g) squares_[g].add(other.squares_[g]);
}

bool learnsLightChoice(const Scene& scene) {
  bool present[3] = {false, false, false};
  for (uint32_t i = 0; i < scene.lights.size(); ++i)
    if (scene.lightDistribution.pmf(i) > 0) present[lightGroup(scene.lights[i].type)] = true;
  return scene.nearbyLights.empty() && int(present[0]) + int(present[1]) + int(present[2]) >= 2;
}

Distribution1D learntLightChoice(const Scene& scene, const LightMoments& moments) {
  const Distribution1D& power = scene.lightDistribution;
  double share[LightMoments::kGroups] = {0, 0, 0}, learnt[LightMoments::kGroups], total = 0;
  for (uint32_t i = 0; i < scene.lights.size(); ++i) share[lightGroup(scene.lights[i].type)] += power.pmf(i);
  for (int g = 0; g < LightMoments::kGroups; ++g) total += learnt[g] = std::sqrt(share[g] * moments.squares_[g].value());
  if (!(total > 0)) return power;  // the pilot's light samples brought nothing: by power
  std::vector<float> weights(scene.lights.size());
  for (uint32_t i = 0; i < scene.lights.size(); ++i) {
    const int g = lightGroup(scene.lights[i].type);
    const double groupShare = (1 - kPowerShare) * learnt[g] / total + kPowerShare * share[g];
    weights[i] = share[g] > 0 ? float(power.pmf(i) * groupShare / share[g]) : 0.0f;
  }
  return lightChoiceOf(scene.lights, weights);
}

}  // namespace lucent
