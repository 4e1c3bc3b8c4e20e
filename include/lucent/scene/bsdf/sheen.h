// KHR_materials_sheen's layer: the "Charlie" sheen of Conty Estevez and Kulla (2017, "Production
// Friendly Microfacet Sheen BRDF"), as the extension's implementation notes give it, on top of a base
// BRDF scaled so that the pair never reflects more than it receives:
//   f = sheenColour D V + base * min(1 - max3(sheenColour) E(n.wo), 1 - max3(sheenColour) E(n.wi)),
//   D = (2 + 1/a) sin(theta_h)^(1/a) / (2 pi),   a = sheenRoughness^2,
//   V = 1 / ((1 + Lambda(n.wo) + Lambda(n.wi)) 4 |n.wo| |n.wi|)   (the paper's fitted Lambda),
// E(mu) the directional albedo of D V (sheenTable: computed here by quadrature, as the extension
// leaves the table to the implementation). Both terms and the scaling are symmetric in wo and wi.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>

#include "lucent/core/math.h"

namespace lucent {

// The smallest sheen roughness rendered: 1/a grows without bound as the roughness goes to 0, and
// D's peak with it; at 0.03 (a = 0.0009) the fibres' lobe is a sliver at grazing angles.
constexpr float kMinSheenRoughness = 0.03f;

inline float charlieD(float alpha, float cosH) {
  const float inverse = 1.0f / alpha;
  const float sin2 = std::max(0.0f, 1.0f - cosH * cosH);
  return (2.0f + inverse) * std::pow(sin2, 0.5f * inverse) * (0.5f * kInvPi);
}

// The paper's fit of ln Lambda for cos theta in [0, 0.5], its five coefficients interpolated in
// (1 - a)^2 between those fitted at a = 0 and a = 1.
inline float sheenLogLambdaFit(float x, float alpha) {
  const float t = (1.0f - alpha) * (1.0f - alpha);
  const float a = 21.5473f + (25.3245f - 21.5473f) * t;
  const float b = 3.82987f + (3.32435f - 3.82987f) * t;
  const float c = 0.19823f + (0.16801f - 0.19823f) * t;
  const float d = -1.97760f + (-1.27393f + 1.97760f) * t;
  const float e = -4.32054f + (-4.85967f + 4.32054f) * t;
  return a / (1.0f + b * std::pow(x, c)) + d * x + e;
}

// Lambda(cos theta): the fit below 0.5, mirrored about it above (the paper's extension to the
// whole hemisphere).
inline float sheenLambda(float cosTheta, float alpha) {
  const float c = std::abs(cosTheta);
  return c < 0.5f ? std::exp(sheenLogLambdaFit(c, alpha))
                  : std::exp(2.0f * sheenLogLambdaFit(0.5f, alpha) - sheenLogLambdaFit(1.0f - c, alpha));
}

// D V for directions above the surface (woZ, wiZ > 0), h their half vector: the sheen BRDF of a
// white sheen colour.
inline float sheenValue(float alpha, float woZ, float wiZ, float cosH) {
  return charlieD(alpha, cosH) / ((1.0f + sheenLambda(woZ, alpha) + sheenLambda(wiZ, alpha)) * (4.0f * woZ * wiZ));
}

// E(mu, roughness): the directional albedo of sheenValue, tabulated on a grid of sqrt(mu) (E climbs
// steeply towards grazing angles) and roughness and read bilinearly. The table is made once, on
// first use, by the midpoint rule over the hemisphere (in theta finer than in phi: D is sharp in
// theta_h at small roughness).
class SheenAlbedoTable {
 public:
  static constexpr int kCosines = 64, kRoughnesses = 16;

  static const SheenAlbedoTable& get() {
    static const SheenAlbedoTable table;
    return table;
  }

  float at(float cosTheta, float roughness) const {
    const float x = std::sqrt(std::clamp(cosTheta, 0.0f, 1.0f)) * (kCosines - 1);
    const float y = std::clamp(roughness, 0.0f, 1.0f) * (kRoughnesses - 1);
    const int i = std::min(int(x), kCosines - 2), j = std::min(int(y), kRoughnesses - 2);
    const float fx = x - float(i), fy = y - float(j);
    const auto e = [&](int a, int b) { return values_[size_t(b * kCosines + a)]; };
    return (1 - fy) * ((1 - fx) * e(i, j) + fx * e(i + 1, j)) + fy * ((1 - fx) * e(i, j + 1) + fx * e(i + 1, j + 1));
  }

  // The quadrature the table is made with, for a cosine and roughness of the grid or not.
  static float integrate(float cosTheta, float roughness) {
    const float mu = std::max(cosTheta, 1e-3f), r = std::max(roughness, kMinSheenRoughness);
    const float alpha = r * r;
    const Vec3 wo{std::sqrt(1.0f - mu * mu), 0.0f, mu};
    constexpr int kTheta = 128, kPhi = 48;  // phi over [0, pi], doubled: the lobe is symmetric in y
    double sum = 0;
    for (int i = 0; i < kTheta; ++i) {
      const double theta = (i + 0.5) * (kPi / 2) / kTheta;
      const float cosT = float(std::cos(theta)), sinT = float(std::sin(theta));
      double ring = 0;
      for (int j = 0; j < kPhi; ++j) {
        const double phi = (j + 0.5) * kPi / kPhi;
        const Vec3 wi{sinT * float(std::cos(phi)), sinT * float(std::sin(phi)), cosT};
        ring += sheenValue(alpha, wo.z, wi.z, normalize(wo + wi).z) * cosT;
      }
      sum += ring * std::sin(theta);
    }
    return float(sum * (kPi / 2 / kTheta) * (kPi / kPhi) * 2);
  }

 private:
  SheenAlbedoTable() {
    for (int j = 0; j < kRoughnesses; ++j)
      for (int i = 0; i < kCosines; ++i)
        values_[size_t(j * kCosines + i)] =
            integrate(float(i * i) / float((kCosines - 1) * (kCosines - 1)), float(j) / (kRoughnesses - 1));
  }
  std::array<float, size_t(kCosines) * kRoughnesses> values_{};
};

}  // namespace lucent
