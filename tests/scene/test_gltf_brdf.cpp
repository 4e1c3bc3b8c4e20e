// glTF's metallic-roughness BRDF (bsdf.h, surface.h's gltfBsdf) with its sheen and clear coat
// layers: its value against the specifications' formulas written out independently in double,
// reciprocity (and the coat's lack of it), chi-square tests of its sampling, the directional albedo
// of its sample weights against numerical integration (the furnace, test_bsdfs.h), and the
// limit of small roughness against a mirror.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "chi2.h"
#include "lucent/core/rng.h"
#include "lucent/scene/surface.h"
#include "test_bsdfs.h"

using namespace lucent;
using test::directionAt;

namespace {

// 4 roughnesses x 3 angles x 2 materials (a coloured metal, a rough dielectric), 2 sheen layers x 3
// angles, 2 coat roughnesses x 2 coat normals x 3 angles, and 2 transmitting roughnesses x 3 angles,
// at 1% for the whole file (Sidak); the negative control excluded.
constexpr int kChi2Tests = 48;
const double kAlpha = chi2::sidak(0.01, kChi2Tests);

struct Parameters {
  Rgb base{0.8f, 0.5f, 0.2f};
  float metallic = 0, roughness = 0.5f, ior = 1.5f, specular = 1;
  Rgb specularColour{1.0f};
  GgxMasking masking = GgxMasking::Separable;
  Rgb sheenColour{0.0f};
  float sheenRoughness = 0;
  float clearcoat = 0, clearcoatRoughness = 0;
  Vec3 clearcoatNormal{0, 0, 1};  // in the shading frame
  float transmission = 0;
};

SurfaceBsdf bsdfOf(const Parameters& p) {
  Material m;
  m.type = MaterialType::Gltf;
  m.masking = p.masking;
  m.kd = p.base;
  m.ks = p.specularColour;
  m.ni = p.ior;
  m.specular = p.specular;
  m.metallic = p.metallic, m.roughness = p.roughness;
  m.sheenColour = p.sheenColour, m.sheenRoughness = p.sheenRoughness;
  m.clearcoat = p.clearcoat, m.clearcoatRoughness = p.clearcoatRoughness;
  m.transmission = p.transmission;
  GltfFactors f = gltfFactors(m, p.base);
  f.clearcoatNormal = p.clearcoatNormal;
  return gltfBsdf(m, f);
}

// Appendix B with KHR_materials_ior and KHR_materials_specular, as the specifications write it:
// material = mix(dielectric_brdf, metal_brdf, metallic), dielectric_brdf = F_d specular_brdf + (1 -
// max(F_d)) diffuse_brdf, metal_brdf = F_m specular_brdf, specular_brdf = V D; V in the appendix's
// separable form or the sample renderer's height-correlated one. In double, from scratch.
// With KHR_materials_transmission (thin-walled), base = mix(diffuse_brdf, specular_btdf * baseColor,
// transmission), specular_btdf the specular lobe at H_T = normalize(V - 2 (N.L) N + L), the
// Fresnel term at V.H_T.
double appendixB(const Parameters& p, Vec3 wo, Vec3 wi, int channel) {
  if (wi.z < 0 && p.transmission > 0) {
    const Vec3 mirrored{wi.x, wi.y, -wi.z};
    const double a = double(p.roughness) * p.roughness, a2 = a * a;
    const double nv = wo.z, nl = mirrored.z;
    if (nv <= 0) return 0;
    const double hx = double(wo.x) + mirrored.x, hy = double(wo.y) + mirrored.y, hz = double(wo.z) + mirrored.z;
    const double hl = std::sqrt(hx * hx + hy * hy + hz * hz);
    const double nh = hz / hl, vh = (double(wo.x) * hx + double(wo.y) * hy + double(wo.z) * hz) / hl;
    const double d = a2 / (kPi * std::pow(nh * nh * (a2 - 1) + 1, 2));
    const double v = p.masking == GgxMasking::Separable
                         ? 1 / ((nl + std::sqrt(a2 + (1 - a2) * nl * nl)) * (nv + std::sqrt(a2 + (1 - a2) * nv * nv)))
                         : 0.5 / (nl * std::sqrt(nv * nv * (1 - a2) + a2) + nv * std::sqrt(nl * nl * (1 - a2) + a2));
    const double w = std::pow(1 - std::abs(vh), 5);
    const double r = (double(p.ior) - 1) / (double(p.ior) + 1);
    double fdMax = 0;
    for (int c = 0; c < 3; ++c) {
      const double f0 = std::min(r * r * p.specularColour[c], 1.0) * p.specular;
      fdMax = std::max(fdMax, f0 + (p.specular - f0) * w);
    }
    return (1 - p.metallic) * (1 - fdMax) * p.transmission * p.base[channel] * v * d;
  }
  const double a = double(p.roughness) * p.roughness, a2 = a * a;
  const double nv = wo.z, nl = wi.z;
  if (nv <= 0 || nl <= 0) return 0;
  const double hx = double(wo.x) + wi.x, hy = double(wo.y) + wi.y, hz = double(wo.z) + wi.z;
  const double hl = std::sqrt(hx * hx + hy * hy + hz * hz);
  const double nh = hz / hl, vh = (double(wo.x) * hx + double(wo.y) * hy + double(wo.z) * hz) / hl;
  const double d = a2 / (kPi * std::pow(nh * nh * (a2 - 1) + 1, 2));
  const double v = p.masking == GgxMasking::Separable
                       ? 1 / ((nl + std::sqrt(a2 + (1 - a2) * nl * nl)) * (nv + std::sqrt(a2 + (1 - a2) * nv * nv)))
                       : 0.5 / (nl * std::sqrt(nv * nv * (1 - a2) + a2) + nv * std::sqrt(nl * nl * (1 - a2) + a2));
  const double specularBrdf = v * d;
  const double w = std::pow(1 - std::abs(vh), 5);
  const double r = (double(p.ior) - 1) / (double(p.ior) + 1);
  double f0[3], fd[3];
  for (int c = 0; c < 3; ++c) {
    f0[c] = std::min(r * r * p.specularColour[c], 1.0) * p.specular;
    fd[c] = f0[c] + (p.specular - f0[c]) * w;
  }
  const double fdMax = std::max({fd[0], fd[1], fd[2]});
  const double base = p.base[channel];
  const double dielectric = fd[channel] * specularBrdf + (1 - fdMax) * (1 - p.transmission) * base / kPi;
  const double metal = (base + (1 - base) * w) * specularBrdf;
  return (1 - p.metallic) * dielectric + p.metallic * metal;
}

// The chi-square test of a lobe's sampling against bsdfPdf (two seeds drawn from `seed`), and the
// furnace: the mean sample weight is the directional albedo (numerical integration, test_bsdfs.h),
// within 4.5 standard errors and the rule's 0.2%.
void checkSamplingAndAlbedo(const SurfaceBsdf& b, Vec3 wo, uint64_t& seed) {
  const auto sampler = [&](Rng& rng) {
    const float u = rng.uniform();
    const BsdfSample s = sampleBsdf(b, wo, u, rng.uniform2());
    return s.valid ? chi2::DirectionSample{s.wi, s.pdf} : chi2::DirectionSample{{}, 0.0f};
  };
  chi2::Options opt;
  opt.seed = seed++;
  opt.mass = std::nullopt;
  CHECK_CHI2_PASS(chi2::testSphere(sampler, [&](Vec3 wi) { return bsdfPdf(b, wo, wi); }, opt));
  const Rgb quadrature = test::directionalAlbedo(b, wo);
  const test::MeanWeight m = test::meanSampleWeight(b, wo, 400'000, seed++);
  for (int c = 0; c < 3; ++c) {
    INFO("channel " << c << ": quadrature " << quadrature[c] << ", sampled " << m.mean[c] << " +- " << m.error[c]);
    CHECK(std::abs(m.mean[c] - quadrature[c]) <= 4.5 * m.error[c] + 2e-3 * quadrature[c]);
  }
}

}  // namespace

TEST_CASE("glTF BRDF: the value is Appendix B's metal/dielectric mix with KHR_materials_ior and _specular",
          "[bsdf][gltf]") {
  Rng rng(5);
  for (const GgxMasking masking : {GgxMasking::Separable, GgxMasking::HeightCorrelated})
    for (int i = 0; i < 3000; ++i) {
      Parameters p;
      p.masking = masking;
      p.base = Rgb(rng.uniform(), rng.uniform(), rng.uniform());
      p.metallic = i % 3 == 0 ? 0.0f : i % 3 == 1 ? 1.0f : rng.uniform();
      p.roughness = 0.1f + 0.9f * rng.uniform();
      p.ior = i % 7 == 0 ? 0.0f : 1.0f + 1.5f * rng.uniform();
      p.specular = rng.uniform();
      p.specularColour = Rgb(2 * rng.uniform(), 2 * rng.uniform(), 2 * rng.uniform());
      const SurfaceBsdf b = bsdfOf(p);
      const Vec3 wo = sampleUniformSphere(rng.uniform2()), wi = sampleUniformSphere(rng.uniform2());
      const Rgb f = evalBsdf(b, wo, wi);
      for (int c = 0; c < 3; ++c) {
        INFO("masking " << int(masking) << ", case " << i << ", channel " << c);
        CHECK(f[c] == Approx(appendixB(p, wo, wi, c)).epsilon(2e-4).margin(1e-6));
      }
    }
}

TEST_CASE("glTF BRDF: reciprocal, and zero unless both directions lie above the surface", "[bsdf][gltf]") {
  Rng rng(6);
  for (int i = 0; i < 3000; ++i) {
    Parameters p;
    p.masking = i % 2 ? GgxMasking::Separable : GgxMasking::HeightCorrelated;
    p.metallic = rng.uniform();
    p.roughness = 0.05f + 0.95f * rng.uniform();
    p.specularColour = Rgb(rng.uniform(), rng.uniform(), rng.uniform());
    const SurfaceBsdf b = bsdfOf(p);
    const Vec3 wo = sampleUniformSphere(rng.uniform2()), wi = sampleUniformSphere(rng.uniform2());
    const Rgb f = evalBsdf(b, wo, wi), g = evalBsdf(b, wi, wo);
    for (int c = 0; c < 3; ++c) CHECK(f[c] == Approx(g[c]).epsilon(1e-5).margin(1e-7));
    if (wo.z <= 0 || wi.z <= 0) CHECK(f.isBlack());
  }
}

TEST_CASE("glTF BRDF: sampled directions have the density bsdfPdf gives, and weights f cos / pdf (chi-square)",
          "[bsdf][gltf][chi2]") {
  uint64_t seed = 21;
  for (const float roughness : {0.2f, 0.4f, 0.7f, 1.0f})
    for (const double theta : {0.0, 0.8, 1.4})
      for (const bool metal : {true, false}) {
        Parameters p;
        p.metallic = metal ? 1.0f : 0.0f;
        p.roughness = roughness;
        p.masking = metal ? GgxMasking::Separable : GgxMasking::HeightCorrelated;
        const SurfaceBsdf b = bsdfOf(p);
        const Vec3 wo = directionAt(theta, 0.7);
        INFO("roughness " << roughness << ", theta " << theta << (metal ? ", metal" : ", dielectric"));
        uint64_t wrongWeights = 0;
        const auto sampler = [&](Rng& rng) {
          const float u = rng.uniform();
          const BsdfSample s = sampleBsdf(b, wo, u, rng.uniform2());
          if (!s.valid) return chi2::DirectionSample{{}, 0.0f};
          const BsdfValue v = evalBsdfAndPdf(b, wo, s.wi);
          for (int c = 0; c < 3; ++c) {
            const double expected = double(v.f[c]) * s.wi.z / v.pdf;
            if (!(std::abs(s.weight[c] - expected) <= 1e-4 * expected + 1e-7)) ++wrongWeights;
          }
          return chi2::DirectionSample{s.wi, s.pdf};
        };
        chi2::Options opt;
        opt.seed = seed++;
        opt.mass = std::nullopt;  // directions below the horizon are failures
        if (metal) {
          opt.axis = Vec3{-wo.x, -wo.y, wo.z};
          opt.zMin = std::cos(std::min(double(kPi), 8.0 * roughness * roughness + 0.05));
        }
        CHECK_CHI2_PASS(chi2::testSphere(sampler, [&](Vec3 wi) { return bsdfPdf(b, wo, wi); }, opt));
        CHECK(wrongWeights == 0);
      }
}

TEST_CASE("glTF BRDF: the chi-square test rejects a lobe choice other than the one the pdf states",
          "[bsdf][gltf][chi2]") {
  Parameters p;
  p.roughness = 0.3f;
  p.base = Rgb(0.3f);
  const SurfaceBsdf b = bsdfOf(p);
  const Vec3 wo = directionAt(1.2, 0.2);
  // The specular lobe chosen 1.3 times as often as specularChoice says.
  const float choice = std::min(1.0f, 1.3f * b.gltf.specularChoice(wo.z));
  const auto sampler = [&](Rng& rng) {
    const float u = rng.uniform();
    const Vec2 u2 = rng.uniform2();
    const Vec3 wi = u < choice ? reflect(wo, sampleGgxVisibleNormal(b.gltf.alpha, wo, u2)) : sampleCosineHemisphere(u2);
    return chi2::DirectionSample{wi, wi.z > 0 ? bsdfPdf(b, wo, wi) : 0.0f};
  };
  chi2::Options opt;
  opt.seed = 77;
  opt.mass = std::nullopt;
  CHECK_CHI2_REJECT(chi2::testSphere(sampler, [&](Vec3 wi) { return bsdfPdf(b, wo, wi); }, opt));
}

TEST_CASE("glTF furnace: the sample weights' mean is the directional albedo, metals never reflect more than they "
          "receive, the white dielectric does at grazing angles",
          "[bsdf][gltf]") {
  // The tolerance is 4.5 standard errors of the mean weight, plus the quadrature's own error.
  const int n = 400'000;
  uint64_t seed = 31;
  const auto check = [&](const Parameters& p, double theta) {
    const SurfaceBsdf b = bsdfOf(p);
    const Vec3 wo = directionAt(theta, 0.4);
    const Rgb quadrature = test::directionalAlbedo(b, wo);
    const test::MeanWeight m = test::meanSampleWeight(b, wo, n, seed++);
    for (int c = 0; c < 3; ++c) {
      INFO("metallic " << p.metallic << ", roughness " << p.roughness << ", theta " << theta << ", channel " << c
                       << ": quadrature " << quadrature[c] << ", sampled " << m.mean[c] << " +- " << m.error[c]);
      CHECK(std::abs(m.mean[c] - quadrature[c]) <= 4.5 * m.error[c] + 2e-3 * quadrature[c]);
    }
    return quadrature;
  };
  SECTION("white metals: at most 1, whatever the roughness and angle") {
    Parameters p;
    p.base = Rgb(1.0f);
    p.metallic = 1;
    for (const float roughness : {0.3f, 0.6f, 1.0f})
      for (const double theta : {0.0, 0.7, 1.2, 1.5}) {
        p.roughness = roughness;
        const Rgb a = check(p, theta);
        CHECK(a.maxComponent() <= 1.0f);
        // Smith's masking loses energy (no multiple scattering): more the rougher and more grazing.
        if (roughness == 1.0f && theta == 0.0) CHECK(a.r < 0.9f);
      }
  }
  SECTION("white dielectric (base colour 1, ior 1.5): fresnel_mix reflects more than 1 at grazing view") {
    // Appendix B's fresnel_mix weighs the diffuse base by 1 - F at the half vector of each pair of
    // directions, not by what the specular lobe takes from wo: where wo grazes, the lobe reflects
    // most of the light while the diffuse base keeps nearly all of it, and the sum exceeds the light
    // received. By quadrature, roughness 0.5: 0.997 at normal view, 1.007 at 1.0 rad, 1.052 at 1.3,
    // 1.104 at 1.5; roughness 0.25: 1.017, 1.16, 1.37 at those angles; roughness 1: at most 0.976
    // (masking's loss outweighs it). The specification's model, rendered as written.
    Parameters p;
    p.base = Rgb(1.0f);
    p.roughness = 0.5f;
    const Rgb normal = check(p, 0.0), steep = check(p, 1.0), grazing = check(p, 1.5);
    CHECK(normal.r <= 1.0f);
    CHECK(steep.r > normal.r);
    CHECK(grazing.r > 1.05f);
  }
  SECTION("mixes, coloured and tinted") {
    Parameters p;
    p.metallic = 0.4f;
    p.roughness = 0.45f;
    p.ior = 1.8f;
    p.specular = 0.7f;
    p.specularColour = Rgb(1.5f, 0.5f, 1.0f);
    check(p, 0.3);
    check(p, 1.1);
  }
}

TEST_CASE("glTF BRDF: at the smallest roughness a metal reflects as a mirror with Schlick's Fresnel",
          "[bsdf][gltf]") {
  Parameters p;
  p.base = Rgb(0.9f, 0.6f, 0.3f);
  p.metallic = 1;
  p.roughness = 0;  // rendered at alpha kMinGgxAlpha
  const SurfaceBsdf b = bsdfOf(p);
  REQUIRE(b.gltf.alpha == kMinGgxAlpha);
  Rng rng(41);
  for (const double theta : {0.0, 0.6, 1.2}) {
    const Vec3 wo = directionAt(theta, 1.0);
    const Vec3 mirror{-wo.x, -wo.y, wo.z};
    double sum[3] = {0, 0, 0};
    const int n = 20000;
    int wide = 0;
    for (int i = 0; i < n; ++i) {
      const float u = rng.uniform();
      const BsdfSample s = sampleBsdf(b, wo, u, rng.uniform2());
      REQUIRE(s.valid);
      wide += dot(s.wi, mirror) < std::cos(0.02);
      for (int c = 0; c < 3; ++c) sum[c] += s.weight[c];
    }
    // GGX's tail: a microfacet normal beyond 0.01 rad of the normal with probability about alpha^2 /
    // (alpha^2 + 0.01^2) = 1%, so a reflection beyond 0.02 rad of the mirror direction.
    CHECK(wide < n / 50);
    // A mirror's weight: Schlick's Fresnel at wo.n, times G1 (1 to within alpha^2 tan^2).
    const double w = std::pow(1 - std::cos(theta), 5);
    for (int c = 0; c < 3; ++c) {
      INFO("theta " << theta << ", channel " << c);
      CHECK(sum[c] / n == Approx(p.base[c] + (1 - p.base[c]) * w).epsilon(2e-3));
    }
  }
}

namespace {

// KHR_materials_sheen's layer as the extension's implementation notes write it, in double, from
// scratch: Charlie D, the visibility from the fitted Lambda, and the albedo scaling, E read from
// the lobe's table (its own quadrature is tested against this one's below).
double sheenLayer(const Parameters& p, Vec3 wo, Vec3 wi, int channel) {
  const double nv = wo.z, nl = wi.z;
  if (nv <= 0 || nl == 0 || (nl < 0 && !(p.transmission > 0))) return 0;
  if (nl < 0) {
    // Through the surface: the sheen reflects only, its scaling at |n.wi| still holds the base down.
    const double m = p.sheenColour.maxComponent(), r = std::max(double(p.sheenRoughness), double(kMinSheenRoughness));
    const SheenAlbedoTable& e = SheenAlbedoTable::get();
    const double scaling = std::min(1 - m * e.at(float(nv), float(r)), 1 - m * e.at(float(-nl), float(r)));
    return scaling * appendixB(p, wo, wi, channel);
  }
  const double r = std::max(double(p.sheenRoughness), double(kMinSheenRoughness)), a = r * r;
  const double hx = double(wo.x) + wi.x, hy = double(wo.y) + wi.y, hz = double(wo.z) + wi.z;
  const double nh = hz / std::sqrt(hx * hx + hy * hy + hz * hz);
  const double d = (2 + 1 / a) * std::pow(1 - nh * nh, 0.5 / a) / (2 * kPi);
  const auto l = [&](double x) {
    const double t = (1 - a) * (1 - a);
    return (21.5473 + (25.3245 - 21.5473) * t) / (1 + (3.82987 + (3.32435 - 3.82987) * t) * std::pow(x, 0.19823 + (0.16801 - 0.19823) * t)) +
           (-1.97760 + (-1.27393 + 1.97760) * t) * x + (-4.32054 + (-4.85967 + 4.32054) * t);
  };
  const auto lambda = [&](double c) { return c < 0.5 ? std::exp(l(c)) : std::exp(2 * l(0.5) - l(1 - c)); };
  const double v = 1 / ((1 + lambda(nv) + lambda(nl)) * 4 * nv * nl);
  const double m = p.sheenColour.maxComponent();
  const SheenAlbedoTable& e = SheenAlbedoTable::get();
  const double scaling = std::min(1 - m * e.at(float(nv), float(r)), 1 - m * e.at(float(nl), float(r)));
  return p.sheenColour[channel] * d * v + scaling * appendixB(p, wo, wi, channel);
}

// The directional albedo of the white sheen term D V, by the midpoint rule in double over a grid
// four times finer in each direction than the table's quadrature.
double sheenAlbedo(double mu, double roughness) {
  const double a = roughness * roughness;
  const Vec3 wo{float(std::sqrt(1 - mu * mu)), 0.0f, float(mu)};
  const int nTheta = 512, nPhi = 384;
  double sum = 0;
  for (int i = 0; i < nTheta; ++i) {
    const double theta = (i + 0.5) * (kPi / 2) / nTheta;
    for (int j = 0; j < nPhi; ++j) {
      const double phi = (j + 0.5) * 2 * kPi / nPhi;
      const Vec3 wi{float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta))};
      sum += sheenValue(float(a), wo.z, wi.z, normalize(wo + wi).z) * std::cos(theta) * std::sin(theta);
    }
  }
  return sum * (kPi / 2 / nTheta) * (2 * kPi / nPhi);
}

}  // namespace

TEST_CASE("Sheen: the albedo table is the integral of D V, read between its points", "[bsdf][gltf]") {
  // Off the table's grid (bilinear reading) and on it, against a quadrature 4 x 8 times finer:
  // within 0.004 (the table's reading between 64 cosines and 16 roughnesses, and its coarser rule).
  const SheenAlbedoTable& table = SheenAlbedoTable::get();
  for (const double roughness : {0.2, 0.37, 0.6, 1.0})
    for (const double mu : {0.05, 0.3, 0.55, 0.8, 1.0}) {
      const double expected = sheenAlbedo(mu, roughness);
      INFO("roughness " << roughness << ", cos theta " << mu << ": table " << table.at(float(mu), float(roughness))
                        << ", quadrature " << expected);
      CHECK(expected > 0);
      CHECK(expected < 1);
      CHECK(std::abs(table.at(float(mu), float(roughness)) - expected) <= 0.004);
    }
}

TEST_CASE("Sheen: the layered BRDF is the extension's formula, reciprocal, and zero below the surface",
          "[bsdf][gltf]") {
  Rng rng(8);
  for (int i = 0; i < 3000; ++i) {
    Parameters p;
    p.base = Rgb(rng.uniform(), rng.uniform(), rng.uniform());
    p.metallic = rng.uniform();
    p.roughness = 0.1f + 0.9f * rng.uniform();
    p.sheenColour = Rgb(rng.uniform(), rng.uniform(), rng.uniform());
    p.sheenRoughness = i % 5 == 0 ? 0.0f : rng.uniform();
    p.masking = i % 2 ? GgxMasking::Separable : GgxMasking::HeightCorrelated;
    const SurfaceBsdf b = bsdfOf(p);
    const Vec3 wo = sampleUniformSphere(rng.uniform2()), wi = sampleUniformSphere(rng.uniform2());
    const Rgb f = evalBsdf(b, wo, wi), g = evalBsdf(b, wi, wo);
    for (int c = 0; c < 3; ++c) {
      INFO("case " << i << ", channel " << c);
      CHECK(f[c] == Approx(sheenLayer(p, wo, wi, c)).epsilon(5e-4).margin(1e-6));
      CHECK(f[c] == Approx(g[c]).epsilon(1e-5).margin(1e-7));
    }
    if (wo.z <= 0 || wi.z <= 0) CHECK(f.isBlack());
  }
}

TEST_CASE("Sheen: sampled directions have the density bsdfPdf gives (chi-square), and the furnace", "[bsdf][gltf][chi2]") {
  uint64_t seed = 51;
  for (const float sheenRoughness : {0.3f, 0.8f})
    for (const double theta : {0.2, 0.9, 1.4}) {
      Parameters p;
      p.base = Rgb(0.6f, 0.3f, 0.2f);
      p.roughness = 0.5f;
      p.sheenColour = Rgb(0.9f, 0.8f, 1.0f);
      p.sheenRoughness = sheenRoughness;
      const SurfaceBsdf b = bsdfOf(p);
      const Vec3 wo = directionAt(theta, 0.7);
      INFO("sheen roughness " << sheenRoughness << ", theta " << theta);
      checkSamplingAndAlbedo(b, wo, seed);
    }
}

TEST_CASE("Sheen over a white metal never reflects more than it receives", "[bsdf][gltf]") {
  // The albedo scaling's promise: E(wo) of the sheen plus at most 1 - E(wo) of the base. A white
  // metal (F = 1) under a white sheen, by quadrature, at every angle and both roughnesses.
  for (const float sheenRoughness : {0.25f, 0.7f, 1.0f})
    for (const double theta : {0.0, 0.6, 1.1, 1.45}) {
      Parameters p;
      p.base = Rgb(1.0f);
      p.metallic = 1;
      p.roughness = 0.3f;
      p.sheenColour = Rgb(1.0f);
      p.sheenRoughness = sheenRoughness;
      const Rgb a = test::directionalAlbedo(bsdfOf(p), directionAt(theta, 0.3));
      INFO("sheen roughness " << sheenRoughness << ", theta " << theta << ": albedo " << a.r);
      CHECK(a.r <= 1.0f + 2e-3f);
      CHECK(a.r > 0.5f);
    }
}

namespace {

// KHR_materials_clearcoat's layering as the extension writes it, in double, from scratch:
// mix(material, clearcoat_brdf, clearcoat (0.04 + 0.96 (1 - |V.Nc|)^5)), clearcoat_brdf = D G /
// (4 |V.Nc| |L.Nc|) of alpha clearcoatRoughness^2 about the coat normal Nc, V = wo; the material
// beneath as sheenLayer (Appendix B where there is no sheen). The layer is 0 where L or V is below
// the coat (no microfacet of the coat faces both).
double coatedLayer(const Parameters& p, Vec3 wo, Vec3 wi, int channel) {
  if (wo.z <= 0 || wi.z == 0 || (wi.z < 0 && !(p.transmission > 0))) return 0;
  const double under = sheenLayer(p, wo, wi, channel);
  const Vec3 nc = p.clearcoatNormal;
  const double len = std::sqrt(double(nc.x) * nc.x + double(nc.y) * nc.y + double(nc.z) * nc.z);
  const auto dotNc = [&](double x, double y, double z) { return (x * nc.x + y * nc.y + z * nc.z) / len; };
  const double vn = dotNc(wo.x, wo.y, wo.z), ln = dotNc(wi.x, wi.y, wi.z);
  const double weight = p.clearcoat * (0.04 + 0.96 * std::pow(1 - std::abs(vn), 5));
  double layer = 0;
  if (vn > 0 && ln > 0 && wi.z > 0) {
    const double r = p.clearcoatRoughness, a = std::max(r * r, double(kMinGgxAlpha)), a2 = a * a;
    const double hx = double(wo.x) + wi.x, hy = double(wo.y) + wi.y, hz = double(wo.z) + wi.z;
    const double nh = dotNc(hx, hy, hz) / std::sqrt(hx * hx + hy * hy + hz * hz);
    const double d = a2 / (kPi * std::pow(nh * nh * (a2 - 1) + 1, 2));
    const auto g1 = [&](double c) { return 2 * c / (c + std::sqrt(a2 + (1 - a2) * c * c)); };
    const auto lambda = [&](double c) { return (std::sqrt(1 + a2 * (1 - c * c) / (c * c)) - 1) / 2; };
    const double g = p.masking == GgxMasking::Separable ? g1(vn) * g1(ln) : 1 / (1 + lambda(vn) + lambda(ln));
    layer = d * g / (4 * vn * ln);
  }
  return (1 - weight) * under + weight * layer;
}

// A unit vector tilted from +z by `tilt` towards azimuth phi.
Vec3 tiltedNormal(double tilt, double phi) { return directionAt(tilt, phi); }

}  // namespace

TEST_CASE("Clearcoat: the coated BRDF is the extension's layering about the coat's own normal, zero below the "
          "surface, and not reciprocal",
          "[bsdf][gltf]") {
  Rng rng(9);
  int nonReciprocal = 0;
  for (int i = 0; i < 3000; ++i) {
    Parameters p;
    p.base = Rgb(rng.uniform(), rng.uniform(), rng.uniform());
    p.metallic = rng.uniform();
    p.roughness = 0.1f + 0.9f * rng.uniform();
    if (i % 4 == 0) p.sheenColour = Rgb(rng.uniform(), rng.uniform(), rng.uniform()), p.sheenRoughness = rng.uniform();
    p.clearcoat = i % 5 == 0 ? 1.0f : rng.uniform();
    p.clearcoatRoughness = 0.1f + 0.9f * rng.uniform();
    p.clearcoatNormal = i % 3 == 0 ? Vec3{0, 0, 1} : tiltedNormal(0.5 * rng.uniform(), 2 * kPi * rng.uniform());
    p.masking = i % 2 ? GgxMasking::Separable : GgxMasking::HeightCorrelated;
    const SurfaceBsdf b = bsdfOf(p);
    const Vec3 wo = sampleUniformSphere(rng.uniform2()), wi = sampleUniformSphere(rng.uniform2());
    const Rgb f = evalBsdf(b, wo, wi), g = evalBsdf(b, wi, wo);
    for (int c = 0; c < 3; ++c) {
      INFO("case " << i << ", channel " << c);
      CHECK(f[c] == Approx(coatedLayer(p, wo, wi, c)).epsilon(5e-4).margin(1e-6));
      CHECK(g[c] == Approx(coatedLayer(p, wi, wo, c)).epsilon(5e-4).margin(1e-6));
    }
    if (std::abs(f.r - g.r) > 0.01 * std::max(f.r, g.r)) ++nonReciprocal;
    if (wo.z <= 0 || wi.z <= 0) CHECK(f.isBlack());
  }
  // The weight reads V.Nc, not V.h: f(wo, wi) and f(wi, wo) differ wherever the two cosines do
  // and the coat and the base differ (both directions above the surface in a quarter of the cases).
  CHECK(nonReciprocal > 300);
}

TEST_CASE("Clearcoat: importance transport takes the adjoint f(wi, wo), radiance f(wo, wi)", "[bsdf][gltf]") {
  Rng rng(10);
  int differ = 0, checked = 0;
  for (int i = 0; i < 2000; ++i) {
    Parameters p;
    p.base = Rgb(0.7f, 0.4f, 0.1f);
    p.roughness = 0.2f + 0.8f * rng.uniform();
    p.clearcoat = 1;
    p.clearcoatRoughness = 0.1f + 0.5f * rng.uniform();
    p.clearcoatNormal = tiltedNormal(0.3 * rng.uniform(), 2 * kPi * rng.uniform());
    const SurfaceBsdf b = bsdfOf(p);
    const Vec3 wo = directionAt(1.5 * rng.uniform(), 2 * kPi * rng.uniform());
    const float u = rng.uniform();
    const Vec2 u2 = rng.uniform2();
    const BsdfSample radiance = sampleBsdf(b, wo, u, u2, Transport::Radiance);
    const BsdfSample importance = sampleBsdf(b, wo, u, u2, Transport::Importance);
    REQUIRE(radiance.valid == importance.valid);
    if (!radiance.valid) continue;
    ++checked;
    CHECK(importance.wi == radiance.wi);
    CHECK(importance.pdf == radiance.pdf);
    for (int c = 0; c < 3; ++c) {
      INFO("case " << i << ", channel " << c);
      CHECK(radiance.weight[c] == Approx(coatedLayer(p, wo, radiance.wi, c) * radiance.wi.z / radiance.pdf).epsilon(1e-3));
      CHECK(importance.weight[c] == Approx(coatedLayer(p, importance.wi, wo, c) * importance.wi.z / importance.pdf).epsilon(1e-3));
    }
    differ += std::abs(importance.weight.g - radiance.weight.g) > 1e-3f * radiance.weight.g;
  }
  CHECK(checked > 1500);
  CHECK(differ > 500);
}

TEST_CASE("Clearcoat: sampled directions have the density bsdfPdf gives (chi-square), and the furnace",
          "[bsdf][gltf][chi2]") {
  uint64_t seed = 81;
  for (const float coatRoughness : {0.25f, 0.5f})
    for (const double tilt : {0.0, 0.35})
      for (const double theta : {0.2, 0.9, 1.4}) {
        Parameters p;
        p.base = Rgb(0.6f, 0.3f, 0.2f);
        p.roughness = 0.6f;
        p.sheenColour = Rgb(0.3f, 0.2f, 0.1f);
        p.sheenRoughness = 0.5f;
        p.clearcoat = 0.9f;
        p.clearcoatRoughness = coatRoughness;
        p.clearcoatNormal = tiltedNormal(tilt, 2.0);
        const SurfaceBsdf b = bsdfOf(p);
        const Vec3 wo = directionAt(theta, 0.7);
        INFO("coat roughness " << coatRoughness << ", coat tilt " << tilt << ", theta " << theta);
        checkSamplingAndAlbedo(b, wo, seed);
      }
}

TEST_CASE("Clearcoat over a white metal never reflects more than it receives", "[bsdf][gltf]") {
  // The layering's promise: (1 - Wc) of a base reflecting at most all plus Wc of a coat reflecting
  // at most all. A white metal under a full coat, with and without sheen, by quadrature.
  for (const float coatRoughness : {0.2f, 0.6f})
    for (const double theta : {0.0, 0.6, 1.1, 1.45}) {
      Parameters p;
      p.base = Rgb(1.0f);
      p.metallic = 1;
      p.roughness = 0.3f;
      p.clearcoat = 1;
      p.clearcoatRoughness = coatRoughness;
      const Rgb a = test::directionalAlbedo(bsdfOf(p), directionAt(theta, 0.3));
      p.sheenColour = Rgb(1.0f);
      p.sheenRoughness = 0.5f;
      const Rgb s = test::directionalAlbedo(bsdfOf(p), directionAt(theta, 0.3));
      INFO("coat roughness " << coatRoughness << ", theta " << theta << ": albedo " << a.r << ", with sheen " << s.r);
      CHECK(a.r <= 1.0f + 2e-3f);
      CHECK(s.r <= 1.0f + 2e-3f);
      CHECK(a.r > 0.5f);
    }
}

TEST_CASE("Clearcoat: a lobe taken into a shading frame is the layering about the world coat normal", "[bsdf][gltf]") {
  // bsdfAt's lobe holds the coat normal in world space; inFrame expresses it in the frame every
  // method shades in (turned to the frame's side when the viewer is behind), reframed moves a lobe
  // between frames about one normal (micro-rendering's jittered frames). The value is compared
  // with the layering computed from world-space dot products.
  Rng rng(12);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 n = sampleUniformSphere(rng.uniform2());
    const Frame toN(n);
    const Vec3 nc = toN.toWorld(tiltedNormal(0.4 * rng.uniform(), 2 * kPi * rng.uniform()));
    const bool behind = i % 2 == 1;  // the viewer on the other side: the frame turned to it
    const Frame frame(behind ? -n : n);
    Material m;
    m.type = MaterialType::Gltf;
    m.kd = Rgb(0.5f, 0.4f, 0.3f);
    m.ks = Rgb(1.0f);  // the specular colour, Parameters' default
    m.roughness = 0.5f;
    m.clearcoat = 1;
    m.clearcoatRoughness = 0.3f;
    GltfFactors factors = gltfFactors(m, m.kd);
    factors.clearcoatNormal = nc;
    const SurfaceBsdf world = gltfBsdf(m, factors);
    const SurfaceBsdf local = world.inFrame(frame);
    const Vec3 wo = frame.toWorld(directionAt(1.4 * rng.uniform(), 2 * kPi * rng.uniform()));
    const Vec3 wi = frame.toWorld(directionAt(1.4 * rng.uniform(), 2 * kPi * rng.uniform()));
    // The expected value: Parameters in the frame with the coat normal computed here.
    Parameters p;
    p.base = m.kd, p.roughness = m.roughness, p.clearcoat = 1, p.clearcoatRoughness = 0.3f;
    const Vec3 ncSide = behind ? -nc : nc;
    p.clearcoatNormal = {dot(ncSide, frame.s), dot(ncSide, frame.t), dot(ncSide, frame.n)};
    const double expected = coatedLayer(p, frame.toLocal(wo), frame.toLocal(wi), 1);
    INFO("case " << i);
    CHECK(evalBsdf(local, frame.toLocal(wo), frame.toLocal(wi)).g == Approx(expected).epsilon(1e-3).margin(1e-6));
    // The same lobe about a frame turned about the normal, from the first frame or from world space.
    const float phi = float(2 * kPi * rng.uniform());
    Frame turned = frame;
    turned.s = frame.s * std::cos(phi) + frame.t * std::sin(phi);
    turned.t = frame.t * std::cos(phi) - frame.s * std::sin(phi);
    const Rgb a = evalBsdf(local.reframed(frame, turned), turned.toLocal(wo), turned.toLocal(wi));
    const Rgb b = evalBsdf(world.inFrame(turned), turned.toLocal(wo), turned.toLocal(wi));
    CHECK(a.g == Approx(expected).epsilon(1e-3).margin(1e-6));
    CHECK(b.g == Approx(expected).epsilon(1e-3).margin(1e-6));
  }
}

TEST_CASE("Transmission: thin-walled, the extension's mirrored GGX lobe tinted by the base colour, reciprocal, "
          "through the surface only where the factor is above 0",
          "[bsdf][gltf]") {
  Rng rng(13);
  int through = 0;
  for (int i = 0; i < 3000; ++i) {
    Parameters p;
    p.base = Rgb(rng.uniform(), rng.uniform(), rng.uniform());
    p.metallic = i % 4 == 0 ? 0.0f : rng.uniform();
    p.roughness = 0.1f + 0.9f * rng.uniform();
    p.ior = 1.0f + rng.uniform();
    p.specular = rng.uniform();
    p.transmission = i % 6 == 0 ? 0.0f : rng.uniform();
    if (i % 5 == 0) p.sheenColour = Rgb(rng.uniform(), rng.uniform(), rng.uniform()), p.sheenRoughness = rng.uniform();
    if (i % 7 == 0) p.clearcoat = rng.uniform(), p.clearcoatRoughness = 0.1f + 0.9f * rng.uniform();
    p.masking = i % 2 ? GgxMasking::Separable : GgxMasking::HeightCorrelated;
    const SurfaceBsdf b = bsdfOf(p);
    CHECK(has(b.flags(), BsdfFlags::Transmission) == (p.transmission > 0));
    const Vec3 wo = directionAt(1.5 * rng.uniform(), 2 * kPi * rng.uniform());
    const Vec3 wi = sampleUniformSphere(rng.uniform2());
    const Rgb f = evalBsdf(b, wo, wi);
    // Seen from the other side: both directions turned through the surface.
    const Rgb g = evalBsdf(b, {wi.x, wi.y, -wi.z}, {wo.x, wo.y, -wo.z});
    for (int c = 0; c < 3; ++c) {
      INFO("case " << i << ", channel " << c);
      CHECK(f[c] == Approx(coatedLayer(p, wo, wi, c)).epsilon(5e-4).margin(1e-6));
      if (wi.z < 0 && p.clearcoat == 0) CHECK(f[c] == Approx(g[c]).epsilon(1e-4).margin(1e-7));
    }
    if (wi.z < 0 && !f.isBlack()) ++through;
    if (wi.z < 0 && p.transmission == 0) CHECK(f.isBlack());
  }
  CHECK(through > 1000);
}

TEST_CASE("Transmission: sampled directions on both sides have the density bsdfPdf gives (chi-square), and the "
          "furnace",
          "[bsdf][gltf][chi2]") {
  uint64_t seed = 101;
  for (const float roughness : {0.2f, 0.6f})
    for (const double theta : {0.2, 1.0, 1.4}) {
      Parameters p;
      p.base = Rgb(0.9f, 0.6f, 0.3f);
      p.roughness = roughness;
      p.transmission = 0.8f;
      p.sheenColour = Rgb(0.2f);
      p.sheenRoughness = 0.5f;
      p.clearcoat = 0.5f;
      p.clearcoatRoughness = 0.3f;
      const SurfaceBsdf b = bsdfOf(p);
      const Vec3 wo = directionAt(theta, 0.7);
      INFO("roughness " << roughness << ", theta " << theta);
      checkSamplingAndAlbedo(b, wo, seed);
    }
}

TEST_CASE("Transmission: a white dielectric that transmits all it does not reflect keeps the energy it receives",
          "[bsdf][gltf]") {
  // Reflected plus transmitted: the specular lobe's albedo E_s plus the mirrored lobe's, (1 - Fd)
  // of it, which sum to about E_s(wo) (every microfacet reflects F and passes 1 - F): near 1 where
  // the GGX lobe loses little to masking, never above 1 + 2e-3 away from grazing views.
  for (const float roughness : {0.1f, 0.4f})
    for (const double theta : {0.0, 0.5, 1.0}) {
      Parameters p;
      p.base = Rgb(1.0f);
      p.roughness = roughness;
      p.transmission = 1;
      const Rgb a = test::directionalAlbedo(bsdfOf(p), directionAt(theta, 0.3));
      INFO("roughness " << roughness << ", theta " << theta << ": albedo " << a.r);
      CHECK(a.r <= 1.0f + 2e-3f);
      CHECK(a.r > 0.9f);
    }
}
