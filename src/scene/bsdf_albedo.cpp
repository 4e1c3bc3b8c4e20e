#include "lucent/scene/bsdf_albedo.h"

#include <cmath>

#include "lucent/core/rng.h"

namespace lucent {

AlbedoEstimate directionalAlbedo(const SurfaceBsdf& bsdf, float cosTheta, uint32_t samples, uint64_t seed) {
  const float sinTheta = std::sqrt(std::max(0.0f, 1.0f - cosTheta * cosTheta));
  const Vec3 wo{sinTheta, 0.0f, cosTheta};
  double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
  for (uint32_t i = 0; i < samples; ++i) {
    Rng rng(seed, i);
    const float lobe = rng.uniform();
    const Vec2 u = rng.uniform2();
    const BsdfSample s = sampleBsdf(bsdf, wo, lobe, u);
    if (!s.valid) continue;
    for (int c = 0; c < 3; ++c) sum[c] += s.weight[c], sum2[c] += double(s.weight[c]) * s.weight[c];
  }
  AlbedoEstimate e;
  const double n = std::max<double>(samples, 1);
  for (int c = 0; c < 3; ++c) {
    const double mean = sum[c] / n;
    const double variance = samples > 1 ? std::max(0.0, (sum2[c] - n * mean * mean) / (n - 1)) : 0.0;
    e.albedo[c] = float(mean);
    e.standardError[c] = float(std::sqrt(variance / n));
  }
  return e;
}

}  // namespace lucent
