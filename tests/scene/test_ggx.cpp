// The GGX distribution and its visible-normal sampling (scene/ggx.h), the base of glTF's
// metallic-roughness material: normalizations integrated numerically, chi-square tests of the
// sampling for several roughnesses and angles, and a wrong sampler that the test must reject.
#include <catch2/catch.hpp>

#include <cmath>

#include "chi2.h"
#include "lucent/core/rng.h"
#include "lucent/scene/ggx.h"

using namespace lucent;

namespace {

// The number of passing chi-square tests below (the negative control excluded), at 1% for the whole
// file (Sidak): 4 roughnesses times 3 angles.
constexpr int kChi2Tests = 12;
const double kAlpha = chi2::sidak(0.01, kChi2Tests);

Vec3 direction(double theta, double phi) {
  return {float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta))};
}

// The integral over the upper hemisphere of f(m) d omega, by the midpoint rule in cos(theta) and phi.
template <class F>
double hemisphereIntegral(F&& f, int thetaCells = 2000, int phiCells = 256) {
  double sum = 0;
  for (int i = 0; i < thetaCells; ++i) {
    const double z = (i + 0.5) / thetaCells, sinTheta = std::sqrt(1 - z * z);
    for (int j = 0; j < phiCells; ++j) {
      const double phi = 2 * kPi * (j + 0.5) / phiCells;
      sum += f(Vec3{float(sinTheta * std::cos(phi)), float(sinTheta * std::sin(phi)), float(z)});
    }
  }
  return sum * (1.0 / thetaCells) * (2 * kPi / phiCells);
}

// Reflection about a visible normal sampled for roughness sampledAlpha, as a chi-square sampler on
// the sphere claiming the density for alpha.
auto reflectionSampler(float alpha, Vec3 wo, float sampledAlpha) {
  return [=](Rng& rng) {
    const Vec3 m = sampleGgxVisibleNormal(sampledAlpha, wo, rng.uniform2());
    const Vec3 wi = normalize(m * (2 * dot(wo, m)) - wo);
    return chi2::DirectionSample{wi, ggxReflectionPdf(alpha, wo, wi)};
  };
}

chi2::Options lobeOptions(float alpha, Vec3 wo, uint64_t seed) {
  chi2::Options opt;
  opt.seed = seed;
  opt.axis = Vec3{-wo.x, -wo.y, wo.z};  // the mirror direction
  // Narrow lobes binned on a cap around it (the rest of the sphere one cell).
  opt.zMin = std::cos(std::min(double(kPi), 8.0 * alpha + 0.05));
  return opt;
}

}  // namespace

TEST_CASE("GGX: D's projected area and every visible-normal distribution integrate to 1", "[ggx]") {
  // Integral of D(m) cos(m) = 1 (the microsurface projects to the macrosurface), and of D_wo(m) = 1
  // for every wo: G1 is Smith's for this D (Heitz 2014, eq. 17). The midpoint rule's error is far
  // below the tolerance for alpha >= 0.1; narrower lobes need finer cells than a test affords.
  for (const float alpha : {0.1f, 0.3f, 0.6f, 1.0f}) {
    INFO("alpha " << alpha);
    CHECK(hemisphereIntegral([&](Vec3 m) { return ggxD(alpha, m.z) * m.z; }) == Approx(1.0).epsilon(2e-3));
    for (const double theta : {0.0, 0.7, 1.3, 1.55}) {
      INFO("theta " << theta);
      const Vec3 wo = direction(theta, 0.4);
      CHECK(hemisphereIntegral([&](Vec3 m) { return ggxVisibleNormalPdf(alpha, wo, m); }) == Approx(1.0).epsilon(2e-3));
    }
  }
}

TEST_CASE("GGX: Smith's masking in Appendix B's form and via Lambda, separable and height-correlated", "[ggx]") {
  for (const float alpha : {0.05f, 0.4f, 1.0f})
    for (const double a : {0.0, 0.5, 1.2, 1.5})
      for (const double b : {0.0, 0.9, 1.4}) {
        const float co = float(std::cos(a)), ci = float(std::cos(b));
        CHECK(smithG1(alpha, co) == Approx(1.0 / (1.0 + smithLambda(alpha, co))).epsilon(1e-5));
        const float separable = smithSeparable(alpha, co, ci), correlated = smithHeightCorrelated(alpha, co, ci);
        CHECK(correlated >= separable * (1 - 1e-6f));
        // Equal where one direction is the normal (Lambda 0 there).
        if (a == 0.0) CHECK(correlated == Approx(separable).epsilon(1e-5));
        // The height-correlated visibility term as GPU renderers write it (0.5 over the sum of
        // each cosine times the other's sqrt(alpha^2 + (1 - alpha^2) cos^2)) is G / (4 cos cos).
        if (co > 0.01f && ci > 0.01f) {
          const double a2 = double(alpha) * alpha;
          const double visibility = 0.5 / (ci * std::sqrt(co * co * (1 - a2) + a2) + co * std::sqrt(ci * ci * (1 - a2) + a2));
          CHECK(correlated / (4.0 * co * ci) == Approx(visibility).epsilon(1e-4));
        }
      }
  // Alpha 1 is a diffuse-like microsurface but masks: G1 < 1 away from the normal.
  CHECK(smithG1(1.0f, 0.5f) < 1.0f);
  CHECK(smithG1(0.3f, 1.0f) == Approx(1.0f));
}

TEST_CASE("GGX: reflection about a sampled visible normal has the density ggxReflectionPdf gives (chi-square)",
          "[ggx][chi2]") {
  uint64_t seed = 11;
  for (const float roughness : {0.2f, 0.5f, 0.8f, 1.0f})
    for (const double theta : {0.0, 0.8, 1.4}) {
      const float alpha = roughness * roughness;
      const Vec3 wo = direction(theta, 1.1);
      INFO("roughness " << roughness << ", theta " << theta);
      CHECK_CHI2_PASS(chi2::testSphere(reflectionSampler(alpha, wo, alpha), [&](Vec3 wi) { return ggxReflectionPdf(alpha, wo, wi); },
                                       lobeOptions(alpha, wo, seed++)));
    }
}

TEST_CASE("GGX: the chi-square test rejects a sampler of another roughness", "[ggx][chi2]") {
  const float alpha = 0.25f;
  const Vec3 wo = direction(0.8, 0.3);
  CHECK_CHI2_REJECT(chi2::testSphere(reflectionSampler(alpha, wo, alpha * 1.1f),
                                     [&](Vec3 wi) { return ggxReflectionPdf(alpha, wo, wi); },
                                     lobeOptions(alpha, wo, 99)));
}
