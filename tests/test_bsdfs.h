// BSDFs and directions that several test files build, and the directional albedo by quadrature.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "lucent/core/rng.h"
#include "lucent/scene/bsdf.h"

namespace lucent::test {

inline Vec3 directionAt(double theta, double phi) {
  return {float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta))};
}

inline SurfaceBsdf diffuseBsdf(Rgb kd) { return LambertianLobe{kd}; }

inline SurfaceBsdf phongBsdf(Rgb kd, Rgb ks, float ns) { return PhongLobe{kd, ks, ns}; }

// The mean of sampleBsdf's weights (what a path tracer multiplies by, or with Transport::Importance
// a photon; invalid samples weigh 0) and its standard error, per channel.
struct MeanWeight {
  double mean[3] = {0, 0, 0}, error[3] = {0, 0, 0};
};
inline MeanWeight meanSampleWeight(const SurfaceBsdf& b, Vec3 wo, int n, uint64_t seed,
                                   Transport transport = Transport::Radiance) {
  Rng rng(seed);
  double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const float u = rng.uniform();
    const BsdfSample s = sampleBsdf(b, wo, u, rng.uniform2(), transport);
    if (!s.valid) continue;
    for (int c = 0; c < 3; ++c) sum[c] += s.weight[c], sum2[c] += double(s.weight[c]) * s.weight[c];
  }
  MeanWeight m;
  for (int c = 0; c < 3; ++c) {
    m.mean[c] = sum[c] / n;
    m.error[c] = std::sqrt(std::max(0.0, sum2[c] / n - m.mean[c] * m.mean[c]) / n);
  }
  return m;
}

// Directional albedo a(wo) = integral of f(wo, wi) |cos(theta_i)| over the hemisphere, per channel,
// by the midpoint rule in coordinates centred on the mirror direction (where the Phong lobe is
// narrow), fine enough to resolve cos^1000; for a lobe that transmits (not a delta), over the
// hemisphere below too, each direction there the mirror image of one above (a thin-walled lobe's
// transmission peaks about the mirror direction's image).
inline Rgb directionalAlbedo(const SurfaceBsdf& b, Vec3 wo) {
  const bool through = has(b.flags(), BsdfFlags::Transmission) && !b.isDelta();
  const Frame lobe(reflect(wo, {0, 0, 1}));
  const int nAlpha = 6000, nPhi = 360;
  double sum[3] = {0, 0, 0};
  for (int i = 0; i < nAlpha; ++i) {
    const double alpha = (i + 0.5) * kPi / nAlpha;
    double ring[3] = {0, 0, 0};
    for (int j = 0; j < nPhi; ++j) {
      const Vec3 wi = lobe.toWorld(directionAt(alpha, (j + 0.5) * 2 * kPi / nPhi));
      if (wi.z <= 0) continue;
      const Rgb f = evalBsdf(b, wo, wi);
      for (int c = 0; c < 3; ++c) ring[c] += f[c] * wi.z;
      if (!through) continue;
      const Rgb t = evalBsdf(b, wo, {wi.x, wi.y, -wi.z});
      for (int c = 0; c < 3; ++c) ring[c] += t[c] * wi.z;
    }
    for (int c = 0; c < 3; ++c) sum[c] += ring[c] * std::sin(alpha);
  }
  const double scale = (kPi / nAlpha) * (2 * kPi / nPhi);
  return Rgb(float(sum[0] * scale), float(sum[1] * scale), float(sum[2] * scale));
}

}  // namespace lucent::test
