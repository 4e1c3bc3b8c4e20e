// KHR_materials_volume's boundary (bsdf/gltf_metal_rough.h): Walter et al. 2007's refraction with
// the extension's Fresnel cases, and the reflection inside, against the formulas written anew in
// double; generalized reciprocity; chi-square tests of its sampling from both sides with the
// furnace; the flux a white boundary keeps; the index-matched boundary's straight pass.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "chi2.h"
#include "lucent/core/rng.h"
#include "lucent/scene/surface.h"
#include "test_bsdfs.h"

using namespace lucent;
using test::directionAt;

namespace {

// 2 roughnesses x 3 angles x 2 sides, at 1% for the whole file (Sidak).
constexpr int kChi2Tests = 12;
const double kAlpha = chi2::sidak(0.01, kChi2Tests);

struct Volume {
  Rgb base{0.9f, 0.7f, 0.4f};
  float metallic = 0, roughness = 0.4f, ior = 1.5f, specular = 1, transmission = 1;
  Rgb sheenColour{0.0f};
  float sheenRoughness = 0, clearcoat = 0, clearcoatRoughness = 0;
  bool bounds = true;  // false: the same material thin-walled
};

SurfaceBsdf volumeBsdf(const Volume& v) {
  Material m;
  m.type = MaterialType::Gltf;
  m.kd = v.base;
  m.ks = Rgb(1.0f);
  m.ni = v.ior;
  m.specular = v.specular;
  m.metallic = v.metallic, m.roughness = v.roughness;
  m.transmission = v.transmission;
  m.sheenColour = v.sheenColour, m.sheenRoughness = v.sheenRoughness;
  m.clearcoat = v.clearcoat, m.clearcoatRoughness = v.clearcoatRoughness;
  m.boundsVolume = v.bounds ? 1 : 0;
  return materialBsdf(m);
}

struct DoubleVec {
  double x, y, z;
};
double dotD(DoubleVec a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// GGX's D and the separable Smith term (Appendix B) of alpha = roughness^2, in double.
double ggxDDouble(double alpha, double cosH) {
  const double a2 = alpha * alpha;
  return cosH > 0 ? a2 / (kPi * std::pow(cosH * cosH * (a2 - 1) + 1, 2)) : 0;
}
double smithDouble(double alpha, double cosO, double cosI) {
  const double a2 = alpha * alpha;
  const auto g1 = [&](double c) { return 2 * c / (c + std::sqrt(a2 + (1 - a2) * c * c)); };
  return g1(std::abs(cosO)) * g1(std::abs(cosI));
}
// The Schlick weight of the extension's three cases for the viewer wo at the microfacet normal h:
// the cosine outside; -1 for total internal reflection.
double schlickCase(const Volume& v, Vec3 wo, DoubleVec h) {
  const double c = std::abs(dotD(h, wo));
  if (wo.z > 0) return std::pow(1 - c, 5);
  const double sin2 = double(v.ior) * v.ior * (1 - c * c);
  return sin2 >= 1 ? -1 : std::pow(1 - std::sqrt(1 - sin2), 5);
}
// The dielectric's F0 (specular colour 1), its largest channel Fd's, at Schlick weight w.
double dielectricFresnel(const Volume& v, double w) {
  const double r = (double(v.ior) - 1) / (double(v.ior) + 1), f0 = std::min(r * r, 1.0) * v.specular;
  return w < 0 ? 1 : f0 + (v.specular - f0) * w;
}

// f(wo, wi) for wo and wi on opposite sides: (1 - metallic) base transmission (1 - Fd) times
// Walter's BTDF for radiance, |wo.h| |wi.h| / (|n.wo| |n.wi|) eta_o^2 D G / (eta_o wo.h + eta_i
// wi.h)^2, h along -(eta_o wo + eta_i wi) turned outwards.
double refracted(const Volume& v, Vec3 wo, Vec3 wi, int channel) {
  const double etaO = wo.z > 0 ? 1 : v.ior, etaI = wo.z > 0 ? v.ior : 1;
  DoubleVec h{etaO * wo.x + etaI * wi.x, etaO * wo.y + etaI * wi.y, etaO * wo.z + etaI * wi.z};
  const double len = std::sqrt(h.x * h.x + h.y * h.y + h.z * h.z) * (h.z < 0 ? -1 : 1);
  h = {h.x / len, h.y / len, h.z / len};
  const double oh = dotD(h, wo), ih = dotD(h, wi);
  if (oh * wo.z <= 0 || ih * wi.z <= 0) return 0;
  const double alpha = std::max(double(v.roughness) * v.roughness, double(kMinGgxAlpha));
  const double btdf = std::abs(oh * ih) / std::abs(double(wo.z) * wi.z) * etaO * etaO * ggxDDouble(alpha, h.z) *
                      smithDouble(alpha, wo.z, wi.z) / std::pow(etaO * oh + etaI * ih, 2);
  return (1 - v.metallic) * v.base[channel] * v.transmission * (1 - dielectricFresnel(v, schlickCase(v, wo, h))) * btdf;
}

// f(wo, wi) for both below: F D G / (4 |n.wo| |n.wi|), F the metal/dielectric mix's Fresnel term
// at the case's weight, 1 for total internal reflection.
double internallyReflected(const Volume& v, Vec3 wo, Vec3 wi, int channel) {
  DoubleVec h{-(double(wo.x) + wi.x), -(double(wo.y) + wi.y), -(double(wo.z) + wi.z)};
  const double len = std::sqrt(h.x * h.x + h.y * h.y + h.z * h.z);
  h = {h.x / len, h.y / len, h.z / len};
  const double w = schlickCase(v, wo, h);
  const double r = (double(v.ior) - 1) / (double(v.ior) + 1), f0 = std::min(r * r, 1.0) * v.specular;
  const double ks = f0 * (1 - v.metallic) + v.base[channel] * v.metallic;
  const double f90 = v.specular * (1 - v.metallic) + v.metallic;
  const double F = w < 0 ? 1 : ks + (f90 - ks) * w;
  const double alpha = std::max(double(v.roughness) * v.roughness, double(kMinGgxAlpha));
  return F * ggxDDouble(alpha, h.z) * smithDouble(alpha, wo.z, wi.z) / (4 * std::abs(double(wo.z) * wi.z));
}

// Integral of f(wo, wi) |n.wi| over the sphere (or with `adjoint` of f(wi, wo) |n.wi|, the flux a
// photon arriving from wo leaves with), by the midpoint rule in polar coordinates about wo's
// mirror direction on wo's side and about its refraction through the macro surface on the other
// (straight through where it is totally reflected), where the lobes peak.
Rgb sphereAlbedo(const SurfaceBsdf& b, Vec3 wo, float ior, bool adjoint = false) {
  const float eta = wo.z > 0 ? 1.0f / ior : ior;
  const float sin2 = eta * eta * (1.0f - wo.z * wo.z);
  const float side = wo.z > 0 ? -1.0f : 1.0f;
  const Vec3 refractedAxis = sin2 < 1.0f ? normalize(Vec3{-eta * wo.x, -eta * wo.y, side * std::sqrt(1.0f - sin2)})
                                         : Vec3{0, 0, side};
  double sum[3] = {0, 0, 0};
  for (const Vec3 axis : {Vec3{-wo.x, -wo.y, wo.z}, refractedAxis}) {
    const bool sameSide = axis.z * wo.z > 0;
    const Frame frame(axis);
    const int nAlpha = 3000, nPhi = 360;
    for (int i = 0; i < nAlpha; ++i) {
      const double alpha = (i + 0.5) * kPi / nAlpha;
      double ring[3] = {0, 0, 0};
      for (int j = 0; j < nPhi; ++j) {
        const Vec3 wi = frame.toWorld(directionAt(alpha, (j + 0.5) * 2 * kPi / nPhi));
        if (sameSide ? !(wi.z * wo.z > 0) : !(wi.z * wo.z < 0)) continue;
        const Rgb f = adjoint ? evalBsdf(b, wi, wo) : evalBsdf(b, wo, wi);
        for (int c = 0; c < 3; ++c) ring[c] += f[c] * std::abs(wi.z);
      }
      for (int c = 0; c < 3; ++c) sum[c] += ring[c] * std::sin(alpha);
    }
  }
  const double scale = (kPi / 3000) * (2 * kPi / 360);
  return Rgb(float(sum[0] * scale), float(sum[1] * scale), float(sum[2] * scale));
}

Vec3 insideAt(double theta, double phi) {
  const Vec3 w = directionAt(theta, phi);
  return {w.x, w.y, -w.z};
}

}  // namespace

TEST_CASE("Volume: refraction is Walter's BTDF with the extension's Fresnel cases, inside reflects by F, outside "
          "reflects as a thin wall, and the boundary is reciprocal up to eta^2",
          "[bsdf][gltf]") {
  Rng rng(17);
  int through = 0, inside = 0, totallyReflected = 0;
  for (int i = 0; i < 3000; ++i) {
    Volume v;
    v.base = Rgb(rng.uniform(), rng.uniform(), rng.uniform());
    v.metallic = i % 3 == 0 ? 0.0f : rng.uniform();
    v.roughness = 0.15f + 0.85f * rng.uniform();
    v.ior = 1.05f + rng.uniform();
    v.specular = rng.uniform();
    v.transmission = rng.uniform();
    const SurfaceBsdf b = volumeBsdf(v);
    const Vec3 wo = sampleUniformSphere(rng.uniform2()), wi = sampleUniformSphere(rng.uniform2());
    const Rgb f = evalBsdf(b, wo, wi);
    INFO("case " << i);
    CHECK(!has(b.flags(), BsdfFlags::TwoSided));
    if (wo.z * wi.z < 0) {
      for (int c = 0; c < 3; ++c) CHECK(f[c] == Approx(refracted(v, wo, wi, c)).epsilon(2e-3).margin(1e-6));
      if (!f.isBlack()) ++through;
    } else if (wo.z < 0) {
      for (int c = 0; c < 3; ++c) CHECK(f[c] == Approx(internallyReflected(v, wo, wi, c)).epsilon(2e-3).margin(1e-6));
      ++inside;
      const float c = std::abs(dot(wo, normalize(wo + wi)));
      if (v.ior * v.ior * (1 - c * c) >= 1) ++totallyReflected;
    } else {
      Volume thin = v;
      thin.bounds = false;
      const Rgb g = evalBsdf(volumeBsdf(thin), wo, wi);
      for (int c = 0; c < 3; ++c) CHECK(f[c] == g[c]);
    }
    // Generalized reciprocity: f(wo, wi) / eta_wo^2 = f(wi, wo) / eta_wi^2, sheen and coat too.
    Volume layered = v;
    if (i % 2) layered.sheenColour = Rgb(rng.uniform()), layered.sheenRoughness = rng.uniform();
    if (i % 3) layered.clearcoat = rng.uniform(), layered.clearcoatRoughness = 0.2f + 0.8f * rng.uniform();
    const SurfaceBsdf l = volumeBsdf(layered);
    if (wo.z * wi.z < 0 || wo.z < 0) {
      const float etaO = wo.z > 0 ? 1.0f : v.ior, etaI = wi.z > 0 ? 1.0f : v.ior;
      const Rgb forward = evalBsdf(l, wo, wi), backward = evalBsdf(l, wi, wo);
      for (int c = 0; c < 3; ++c)
        CHECK(forward[c] / (etaO * etaO) == Approx(backward[c] / (etaI * etaI)).epsilon(2e-3).margin(1e-6));
    }
  }
  CHECK(through > 250);
  CHECK(inside > 500);
  CHECK(totallyReflected > 50);
}

TEST_CASE("Volume: sampled directions from outside and inside have the density bsdfPdf gives (chi-square), and "
          "the furnace",
          "[bsdf][gltf][chi2]") {
  uint64_t seed = 211;
  for (const bool fromInside : {false, true})
    for (const float roughness : {0.3f, 0.6f})
      for (const double theta : {0.2, 0.7, 1.3}) {
        Volume v;
        v.roughness = roughness;
        v.transmission = 0.8f;
        v.metallic = 0.2f;
        if (!fromInside) {
          v.sheenColour = Rgb(0.2f), v.sheenRoughness = 0.5f;
          v.clearcoat = 0.5f, v.clearcoatRoughness = 0.3f;
        }
        const SurfaceBsdf b = volumeBsdf(v);
        const Vec3 wo = fromInside ? insideAt(theta, 0.7) : directionAt(theta, 0.7);
        INFO((fromInside ? "inside" : "outside") << ", roughness " << roughness << ", theta " << theta);
        uint64_t wrongWeights = 0;
        const auto sampler = [&](Rng& rng) {
          const float u = rng.uniform();
          const BsdfSample s = sampleBsdf(b, wo, u, rng.uniform2());
          if (!s.valid) return chi2::DirectionSample{{}, 0.0f};
          const BsdfValue value = evalBsdfAndPdf(b, wo, s.wi);
          for (int c = 0; c < 3; ++c) {
            const double expected = double(value.f[c]) * std::abs(s.wi.z) / value.pdf;
            if (!(std::abs(s.weight[c] - expected) <= 1e-3 * expected + 1e-6)) ++wrongWeights;
          }
          return chi2::DirectionSample{s.wi, s.pdf};
        };
        chi2::Options opt;
        opt.seed = seed++;
        opt.mass = std::nullopt;
        opt.thetaBins = 20;
        CHECK_CHI2_PASS(chi2::testSphere(sampler, [&](Vec3 wi) { return bsdfPdf(b, wo, wi); }, opt));
        CHECK(wrongWeights == 0);
        const Rgb quadrature = sphereAlbedo(b, wo, v.ior);
        for (const Transport transport : {Transport::Radiance, Transport::Importance}) {
          const Rgb expected = transport == Transport::Radiance ? quadrature : sphereAlbedo(b, wo, v.ior, true);
          const test::MeanWeight m = test::meanSampleWeight(b, wo, 400'000, seed++, transport);
          for (int c = 0; c < 3; ++c) {
            INFO("transport " << int(transport) << ", channel " << c << ": quadrature " << expected[c] << ", sampled "
                              << m.mean[c] << " +- " << m.error[c]);
            CHECK(std::abs(m.mean[c] - expected[c]) <= 4.5 * m.error[c] + 3e-3 * expected[c]);
          }
        }
      }
}

TEST_CASE("Volume: a white boundary keeps the flux it receives from either side, and totally reflects inside "
          "beyond the critical angle",
          "[bsdf][gltf]") {
  // Photons (importance, the adjoint f(wi, wo)) leave with what arrived: each microfacet reflects F
  // and passes 1 - F, the Schlick term the same from both sides, so a photon's weight is Smith's
  // G2 / G1 whichever it takes, 1 but for masking. At roughness 0.1 masking loses below 1e-3 and
  // the mean weight of 200,000 photons says so to 1e-4 (the quadrature cannot resolve so narrow a
  // lobe); at roughness 0.4 it loses more the more grazing the light, as much as a white metal
  // there (up to 15% inside at 1.3 rad), and the quadrature gives the flux.
  uint64_t seed = 5;
  for (const float roughness : {0.1f, 0.4f})
    for (const bool fromInside : {false, true})
      for (const double theta : {0.0, 0.5, 1.0, 1.3}) {
        Volume v;
        v.base = Rgb(1.0f);
        v.roughness = roughness;
        const SurfaceBsdf b = volumeBsdf(v);
        const Vec3 wo = fromInside ? insideAt(theta, 0.3) : directionAt(theta, 0.3);
        INFO((fromInside ? "inside" : "outside") << ", roughness " << roughness << ", theta " << theta);
        Volume metal = v;
        metal.metallic = 1, metal.bounds = false, metal.transmission = 0;
        const Vec3 above{wo.x, wo.y, std::abs(wo.z)};
        const float masked = test::directionalAlbedo(volumeBsdf(metal), above).r;
        if (roughness < 0.2f) {
          const test::MeanWeight m = test::meanSampleWeight(b, wo, 200'000, seed++, Transport::Importance);
          INFO("flux " << m.mean[0] << " +- " << m.error[0] << ", a white metal's " << masked);
          CHECK(m.mean[0] <= 1 + 4.5 * m.error[0] + 1e-4);
          CHECK(m.mean[0] > 0.999 * masked);
        } else {
          const Rgb flux = sphereAlbedo(b, wo, v.ior, true);
          INFO("flux " << flux.r << ", a white metal's " << masked);
          CHECK(flux.r <= 1.0f + 2e-3f);
          CHECK(flux.r > 0.97f * masked);
        }
        if (fromInside && theta > 0.9 && roughness < 0.2f) {
          // Beyond asin(1 / 1.5) = 0.73 rad almost nothing leaves.
          const Rgb all = sphereAlbedo(b, wo, v.ior);
          Volume opaque = v;
          opaque.transmission = 0;
          CHECK(all.r == Approx(sphereAlbedo(volumeBsdf(opaque), wo, v.ior).r).epsilon(0.02));
        }
      }
}

TEST_CASE("Volume: an index-matched boundary passes light straight through, a Dirac delta of weight base (1 - Fd)",
          "[bsdf][gltf]") {
  Volume v;
  v.ior = 1.0f;
  v.roughness = 0.5f;
  const SurfaceBsdf b = volumeBsdf(v);
  CHECK(has(b.flags(), BsdfFlags::Specular));
  CHECK(!b.isDelta());
  Rng rng(5);
  for (int i = 0; i < 200; ++i) {
    const Vec3 wo = sampleUniformSphere(rng.uniform2()), wi = sampleUniformSphere(rng.uniform2());
    if (wo.z * wi.z < 0) CHECK(evalBsdf(b, wo, wi).isBlack());
  }
  for (const bool fromInside : {false, true})
    for (const double theta : {0.0, 0.8, 1.3}) {
      const Vec3 wo = fromInside ? insideAt(theta, 1.1) : directionAt(theta, 1.1);
      // F0 = 0 at index 1, F90 = specular = 1: Fd = (1 - cos)^5.
      const double w = std::pow(1 - std::cos(theta), 5);
      const int n = 200'000;
      double sum[3] = {0, 0, 0};
      int straight = 0;
      for (int k = 0; k < n; ++k) {
        const float u = rng.uniform();
        const BsdfSample s = sampleBsdf(b, wo, u, rng.uniform2());
        if (!s.valid || !s.delta) continue;
        ++straight;
        CHECK(s.wi.x == -wo.x);
        CHECK(s.wi.z == -wo.z);
        for (int c = 0; c < 3; ++c) sum[c] += s.weight[c];
      }
      const double p = double(straight) / n;
      for (int c = 0; c < 3; ++c) {
        const double expected = v.base[c] * (1 - w), mean = sum[c] / n;
        // The weight is the delta's value over its probability p: a Bernoulli mean.
        const double error = expected * std::sqrt((1 - p) / (p * n));
        INFO((fromInside ? "inside" : "outside") << ", theta " << theta << ", channel " << c << ": " << mean
                                                 << " against " << expected);
        CHECK(std::abs(mean - expected) <= 4.5 * error + 1e-6);
      }
    }
}
