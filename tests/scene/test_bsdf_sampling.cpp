// Chi-square tests of BSDF sampling (bsdf.h): the directions sampleBsdf draws for Diffuse and Phong
// against bsdfPdf, its sample weights against evalBsdf, and the glass lobe choice against Fresnel;
// each with negative controls that a wrong sampler claiming the right pdf is rejected.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "chi2.h"
#include "lucent/core/rng.h"
#include "lucent/scene/bsdf.h"
#include "test_bsdfs.h"

using namespace lucent;
using chi2::DirectionSample;
using chi2::IndexSample;

namespace {

// The number of passing chi-square tests below (negative controls excluded): 3 diffuse, 12 Phong,
// 10 glass. At the Sidak-corrected level all pass with probability 0.99 for correct samplers.
constexpr int kChi2Tests = 25;
const double kAlpha = chi2::sidak(0.01, kChi2Tests);

using test::directionAt;
const auto diffuse = &test::diffuseBsdf;
const auto phong = &test::phongBsdf;
SurfaceBsdf glass(float ni) { return GlassLobe{ni}; }

Vec3 mirrorOf(Vec3 wo) { return {-wo.x, -wo.y, wo.z}; }

// Binning for a Phong lobe around the mirror direction: the cap holding all but 1e-3 of cos^n, split
// into the harness's theta x phi cells; the rest of the sphere (diffuse part, lobe tail) is one cell.
chi2::Options lobeOptions(Vec3 wo, float ns, uint64_t seed) {
  chi2::Options opt;
  opt.seed = seed;
  opt.axis = mirrorOf(wo);
  opt.zMin = ns >= 20 ? std::pow(1e-3, 1.0 / (ns + 1)) : -1.0;
  opt.mass = std::nullopt;  // lobe directions below the horizon are failures; the mass is the pdf's integral
  return opt;
}

// The harness's view of sampleBsdf: an invalid sample is a failure. Each valid sample's weight is
// checked against evalBsdf * cos / bsdfPdf (relative 1e-4 per channel), since that is what a path
// tracer multiplies by.
struct WeightCheck {
  uint64_t wrong = 0;
  std::string first;
};
auto bsdfSampler(const SurfaceBsdf& b, Vec3 wo, WeightCheck& check) {
  return [&b, wo, &check](Rng& rng) {
    const float u = rng.uniform();
    const BsdfSample s = sampleBsdf(b, wo, u, rng.uniform2());
    if (!s.valid) return DirectionSample{{}, 0.0f};
    const Rgb f = evalBsdf(b, wo, s.wi);
    const double pdf = bsdfPdf(b, wo, s.wi);
    for (int c = 0; c < 3; ++c) {
      const double expected = f[c] * double(s.wi.z) / pdf;
      if (s.delta || !(std::abs(s.weight[c] - expected) <= 1e-4 * expected) || !(s.weight[c] >= 0)) {
        if (check.wrong++ == 0)
          check.first = "weight " + std::to_string(s.weight[c]) + " but f cos / pdf " + std::to_string(expected) +
                        " at " + chi2::detail::str(s.wi);
        break;
      }
    }
    return DirectionSample{s.wi, s.pdf};
  };
}

// Fresnel reflectance of a smooth dielectric written with Fresnel's sine and tangent laws, in double,
// independently of fresnelDielectric's cosine form; theta on the side of index etaI.
double fresnelReference(double theta, double etaI, double etaT) {
  const double sinT = etaI / etaT * std::sin(theta);
  if (sinT >= 1) return 1;
  if (theta == 0) return std::pow((etaI - etaT) / (etaI + etaT), 2);
  const double t = std::asin(sinT);
  const double rs = std::sin(theta - t) / std::sin(theta + t), rp = std::tan(theta - t) / std::tan(theta + t);
  return 0.5 * (rs * rs + rp * rp);
}

}  // namespace

TEST_CASE("Diffuse sampling: cosine-weighted, whatever wo", "[bsdf][chi2]") {
  const SurfaceBsdf b = diffuse({0.8f, 0.5f, 0.2f});
  uint64_t seed = 1;
  for (double theta : {0.0, 0.7, 1.45}) {
    INFO("theta_o = " << theta);
    const Vec3 wo = directionAt(theta, 0.3);
    auto pdf = [&](Vec3 wi) { return bsdfPdf(b, wo, wi); };
    WeightCheck weights;
    // The cosine hemisphere never falls below the horizon: mass 1.
    const chi2::Options opt{.seed = seed++, .zMin = 0};
    CHECK_CHI2_PASS(chi2::testSphere(bsdfSampler(b, wo, weights), pdf, opt));
    INFO(weights.first);
    CHECK(weights.wrong == 0);
  }
}

TEST_CASE("Phong sampling: Kd/Ks mixtures, exponents 10 to 1000, down to grazing wo", "[bsdf][chi2]") {
  struct Case {
    SurfaceBsdf b;
    std::vector<double> thetas;
  };
  const std::vector<Case> cases{
      {phong(Rgb(0.5f), Rgb(0.5f), 10), {0.0, 0.7, 1.45}},
      {phong(Rgb(0.2f), Rgb(0.8f), 100), {0.3, 1.0, 1.45}},
      {phong(Rgb(0.05f), Rgb(0.95f), 1000), {0.3, 1.0, 1.45}},
      {phong(Rgb(0.0f), Rgb(1.0f), 30), {0.5, 1.45}},  // pure Ks: the lobe is always chosen
      // Coloured: the lobe choice uses channel averages, the weight differs per channel.
      {phong({0.6f, 0.3f, 0.1f}, {0.1f, 0.2f, 0.4f}, 50), {0.9}},
  };
  uint64_t seed = 10;
  for (const Case& c : cases) {
    for (double theta : c.thetas) {
      const SurfaceBsdf& b = c.b;
      INFO("Kd " << b.phong.kd.average() << ", Ks " << b.phong.ks.average() << ", Ns " << b.phong.ns << ", theta_o " << theta);
      const Vec3 wo = directionAt(theta, 2.1);
      auto pdf = [&](Vec3 wi) { return bsdfPdf(b, wo, wi); };
      WeightCheck weights;
      const chi2::Result r = chi2::testSphere(bsdfSampler(b, wo, weights), pdf, lobeOptions(wo, b.phong.ns, seed++));
      CHECK_CHI2_PASS(r);
      INFO(weights.first);
      CHECK(weights.wrong == 0);
      // Grazing wo puts part of the lobe below the horizon, where the sampler fails.
      if (theta > 1.4 && b.phong.ns <= 100) CHECK(r.failures > 0);
    }
  }
}

TEST_CASE("Phong pdf and value match the mixture formula", "[bsdf]") {
  // The chi-square tests check the sampler against bsdfPdf; this checks bsdfPdf and evalBsdf against the
  // model itself: pdf = pd cos/pi + (1 - pd) (n+1)/(2 pi) cos^n(alpha), pd = avg(Kd) / (avg(Kd) + avg(Ks)),
  // f = Kd/pi + Ks (n+2)/(2 pi) cos^n(alpha).
  const SurfaceBsdf b = phong({0.6f, 0.3f, 0.1f}, {0.1f, 0.2f, 0.4f}, 50);
  const double pd = (0.6 + 0.3 + 0.1) / (0.6 + 0.3 + 0.1 + 0.1 + 0.2 + 0.4);
  Rng rng(3);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 wo = sampleUniformSphere(rng.uniform2()), wi = sampleUniformSphere(rng.uniform2());
    const double cosAlpha = 2.0 * wo.z * wi.z - dot(wo, wi);  // (2 (wo.n) n - wo) . wi
    const bool above = wo.z > 0 && wi.z > 0;
    const double lobe = cosAlpha > 0 ? std::pow(cosAlpha, 50.0) / (2 * kPi) : 0.0;
    const double pdf = above ? pd * wi.z / kPi + (1 - pd) * 51 * lobe : 0.0;
    CHECK(bsdfPdf(b, wo, wi) == Approx(pdf).epsilon(1e-4).margin(1e-6));
    for (int c = 0; c < 3; ++c) {
      const double f = above ? b.phong.kd[c] / kPi + b.phong.ks[c] * 52 * lobe : 0.0;
      CHECK(evalBsdf(b, wo, wi)[c] == Approx(f).epsilon(1e-4).margin(1e-6));
    }
  }
}

TEST_CASE("Phong sampling: negative controls", "[bsdf][chi2]") {
  const Vec3 wo = directionAt(0.7, 0.4);
  WeightCheck ignored;
  // The sampler of `wrong` claiming the pdf of `right`: only the histogram can tell them apart.
  auto testWrongSampler = [&](const SurfaceBsdf& right, const SurfaceBsdf& wrong, uint64_t seed) {
    auto pdf = [&](Vec3 wi) { return bsdfPdf(right, wo, wi); };
    auto sampler = [&, s = bsdfSampler(wrong, wo, ignored)](Rng& rng) {
      DirectionSample d = s(rng);
      if (d.pdf > 0) d.pdf = pdf(d.direction);
      return d;
    };
    return chi2::testSphere(sampler, pdf, lobeOptions(wo, 100, seed));
  };
  SECTION("lobe chosen with probability 0.75 instead of 0.8") {
    CHECK_CHI2_REJECT(testWrongSampler(phong(Rgb(0.2f), Rgb(0.8f), 100), phong(Rgb(0.25f), Rgb(0.75f), 100), 101));
  }
  SECTION("exponent 110 checked as 100") {
    CHECK_CHI2_REJECT(testWrongSampler(phong(Rgb(0.2f), Rgb(0.8f), 100), phong(Rgb(0.2f), Rgb(0.8f), 110), 102));
  }
  SECTION("lobe sampled around the normal instead of the mirror direction") {
    const SurfaceBsdf b = phong(Rgb(0.5f), Rgb(0.5f), 10);
    const Vec3 wo2 = directionAt(0.5, 0.4);
    auto pdf = [&](Vec3 wi) { return bsdfPdf(b, wo2, wi); };
    auto sampler = [&](Rng& rng) {
      const float u = rng.uniform();
      const Vec2 u2 = rng.uniform2();
      const Vec3 wi = u < b.phong.diffuseChoice() ? sampleCosineHemisphere(u2) : samplePhongLobe(u2, b.phong.ns);
      return DirectionSample{wi, pdf(wi)};
    };
    CHECK_CHI2_REJECT(chi2::testSphere(sampler, pdf, lobeOptions(wo2, 10, 103)));
  }
}

TEST_CASE("Glass: reflection and refraction chosen with probabilities F and 1 - F", "[bsdf][chi2]") {
  struct Case {
    float ni;
    double theta;  // angle of wo to the normal, on its own side
    bool inside;
  };
  std::vector<Case> cases;
  for (double theta : {0.0, 0.5, 1.0, 1.4, 1.55}) cases.push_back({1.5f, theta, false});
  for (double theta : {0.3, 0.6, 0.72}) cases.push_back({1.5f, theta, true});  // critical angle 0.7297
  cases.push_back({2.4f, 0.8, false});
  cases.push_back({1.33f, 0.6, true});  // critical angle 0.8505

  uint64_t seed = 200;
  for (const Case& c : cases) {
    const SurfaceBsdf b = glass(c.ni);
    const double etaI = c.inside ? c.ni : 1.0, etaT = c.inside ? 1.0 : c.ni;
    const Vec3 up = directionAt(c.theta, 0.8);
    const Vec3 wo = c.inside ? Vec3(up.x, up.y, -up.z) : up;
    const double F = fresnelReference(c.theta, etaI, etaT);
    INFO("Ni " << c.ni << ", theta_o " << c.theta << (c.inside ? " inside" : " outside") << ", F = " << F);
    // Each sample must be the mirror direction with weight 1, or Snell's refraction with weight
    // (eta_i / eta_t)^2, on the far side.
    uint64_t wrongDirections = 0;
    auto sampler = [&](Rng& rng) {
      const float u = rng.uniform();
      const BsdfSample s = sampleBsdf(b, wo, u, rng.uniform2());
      if (!s.valid || !s.delta) return IndexSample{0, 0.0f};
      const bool reflected = (s.wi.z > 0) == (wo.z > 0);
      bool ok = std::abs(length(s.wi) - 1) < 1e-5f;
      if (reflected) {
        ok = ok && length(s.wi - mirrorOf(wo)) < 1e-6f && s.weight == Rgb(1.0f);
      } else {
        const double sinT = std::sqrt(double(s.wi.x) * s.wi.x + double(s.wi.y) * s.wi.y);
        ok = ok && std::abs(etaT * sinT - etaI * std::sin(c.theta)) < 1e-5 &&
             dot(Vec3(s.wi.x, s.wi.y, 0), Vec3(wo.x, wo.y, 0)) <= 0 &&
             std::abs(s.weight.g - etaI * etaI / (etaT * etaT)) < 1e-5 && s.weight.r == s.weight.g &&
             s.weight.b == s.weight.g;
      }
      wrongDirections += !ok;
      return IndexSample{reflected ? 0u : 1u, s.pdf};
    };
    auto pmf = [&](uint32_t i) { return float(i == 0 ? F : 1 - F); };
    CHECK_CHI2_PASS(chi2::testDiscrete(sampler, pmf, 2, {.samples = 200'000, .seed = seed++}));
    CHECK(wrongDirections == 0);
  }
}

TEST_CASE("Glass: total internal reflection beyond the critical angle", "[bsdf]") {
  for (float ni : {1.33f, 1.5f, 2.4f}) {
    const double critical = std::asin(1.0 / ni);
    for (double theta : {critical + 0.01, 1.0, 1.5}) {
      INFO("Ni " << ni << ", theta " << theta);
      const Vec3 up = directionAt(theta, 0.3), wo(up.x, up.y, -up.z);
      for (float u : {0.0f, 0.5f, 0.999f}) {
        const BsdfSample s = sampleBsdf(glass(ni), wo, u, {0.5f, 0.5f});
        CHECK(s.valid);
        CHECK(s.pdf == 1.0f);
        CHECK(s.weight == Rgb(1.0f));
        CHECK(length(s.wi - mirrorOf(wo)) < 1e-6f);
      }
    }
  }
}

TEST_CASE("Glass sampling: negative control", "[bsdf][chi2]") {
  // Schlick's approximation F0 + (1 - F0)(1 - cos)^5 instead of the exact Fresnel term, claiming the
  // exact probabilities: 0.060 against 0.078 at 1 radian.
  const double theta = 1.0, F = fresnelReference(theta, 1.0, 1.5);
  const double schlick = 0.04 + 0.96 * std::pow(1 - std::cos(theta), 5);
  auto pmf = [&](uint32_t i) { return float(i == 0 ? F : 1 - F); };
  auto sampler = [&](Rng& rng) {
    const uint32_t i = rng.uniform() < schlick ? 0 : 1;
    return IndexSample{i, pmf(i)};
  };
  CHECK_CHI2_REJECT(chi2::testDiscrete(sampler, pmf, 2, {.samples = 200'000, .seed = 300}));
}
