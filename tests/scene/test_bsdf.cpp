// The materials' scattering functions: reciprocity, energy conservation by numerical integration,
// and agreement of the sampling weights with the integrated albedo.
#include <catch2/catch.hpp>

#include "lucent/core/rng.h"
#include "lucent/scene/bsdf.h"
#include "lucent/scene/bsdf_albedo.h"
#include "lucent/scene/surface.h"
#include "test_bsdfs.h"

using namespace lucent;

namespace {

using test::directionAt;

SurfaceBsdf phong(float kd, float ks, float ns) { return test::phongBsdf(Rgb(kd), Rgb(ks), ns); }

// Directional albedo (green channel; the tests' BSDFs are grey).
double albedo(const SurfaceBsdf& b, Vec3 wo) { return test::directionalAlbedo(b, wo).g; }

}  // namespace

TEST_CASE("Diffuse and Phong BSDFs are reciprocal", "[bsdf]") {
  Rng rng(42);
  for (const SurfaceBsdf& b : {phong(0.8f, 0.0f, 1.0f), phong(0.3f, 0.7f, 5.0f), phong(0.1f, 0.9f, 200.0f)}) {
    for (int k = 0; k < 1000; ++k) {
      const Vec3 wo = sampleCosineHemisphere(rng.uniform2());
      const Vec3 wi = sampleCosineHemisphere(rng.uniform2());
      const Rgb a = evalBsdf(b, wo, wi), c = evalBsdf(b, wi, wo);
      REQUIRE(a.g == Approx(c.g).epsilon(1e-4).margin(1e-6));
    }
  }
}

TEST_CASE("Normalized Phong conserves energy, and reaches Kd + Ks at normal incidence", "[bsdf]") {
  for (float ns : {1.0f, 10.0f, 100.0f, 1000.0f}) {
    const SurfaceBsdf b = phong(0.0f, 1.0f, ns);
    for (float theta : {0.0f, 0.3f, 0.8f, 1.2f, 1.5f}) {
      const double a = albedo(b, directionAt(theta, 0.4f));
      INFO("Ns " << ns << ", theta " << theta << ": albedo " << a);
      REQUIRE(a <= 1.0 + 2e-3);
      if (theta == 0.0f) REQUIRE(a == Approx(1.0).epsilon(2e-3));
    }
  }
  const SurfaceBsdf mixed = phong(0.4f, 0.6f, 20.0f);
  REQUIRE(albedo(mixed, directionAt(0, 0)) == Approx(1.0).epsilon(2e-3));
  const SurfaceBsdf diffuse = phong(0.7f, 0.0f, 1.0f);
  REQUIRE(albedo(diffuse, directionAt(0.9f, 0)) == Approx(0.7).epsilon(2e-3));
}

TEST_CASE("BSDF sampling weights average to the integrated albedo", "[bsdf]") {
  // E[weight] = albedo is the estimator the path tracer relies on; a pdf that does not match the
  // sampled density shows up here. Tolerance: 5 standard errors of the sample mean.
  Rng rng(9);
  for (const SurfaceBsdf& b : {phong(0.7f, 0.0f, 1.0f), phong(0.5f, 0.5f, 8.0f), phong(0.2f, 0.8f, 300.0f)}) {
    for (float theta : {0.2f, 0.9f, 1.4f}) {
      const Vec3 wo = directionAt(theta, 1.0f);
      const int n = 200000;
      double sum = 0, sum2 = 0;
      for (int k = 0; k < n; ++k) {
        const BsdfSample s = sampleBsdf(b, wo, rng.uniform(), rng.uniform2());
        const double w = s.valid ? s.weight.g : 0.0;
        sum += w;
        sum2 += w * w;
      }
      const double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
      const double expected = albedo(b, wo);
      INFO("Kd " << b.phong.kd.g << " Ks " << b.phong.ks.g << " Ns " << b.phong.ns << " theta " << theta << ": " << mean << " +- " << se
                 << " vs " << expected);
      REQUIRE(std::abs(mean - expected) <= 5 * se + 1e-3);
    }
  }
}

TEST_CASE("Mirror reflects about the normal with weight Ks", "[bsdf]") {
  const SurfaceBsdf m = MirrorLobe{Rgb(0.9f, 0.8f, 0.7f)};
  const Vec3 wo = normalize(Vec3{0.3f, -0.2f, 0.8f});
  const BsdfSample s = sampleBsdf(m, wo, 0.5f, {0.5f, 0.5f});
  REQUIRE(s.valid);
  REQUIRE(s.delta);
  REQUIRE(s.wi.x == Approx(-wo.x));
  REQUIRE(s.wi.y == Approx(-wo.y));
  REQUIRE(s.wi.z == Approx(wo.z));
  REQUIRE(s.weight == m.mirror.tint);
  REQUIRE(evalBsdf(m, wo, s.wi).isBlack());
}

TEST_CASE("Glass: Snell's law, Fresnel split, total internal reflection", "[bsdf]") {
  const SurfaceBsdf g = GlassLobe{1.5f};
  // Fresnel at normal incidence: ((n-1)/(n+1))^2.
  REQUIRE(fresnelDielectric(1.0f, 1.0f, 1.5f) == Approx(0.04f).epsilon(1e-4));
  REQUIRE(fresnelDielectric(0.0f, 1.0f, 1.5f) == Approx(1.0f));
  const float theta = 0.7f;
  const Vec3 wo = directionAt(theta, 0.3f);
  const float F = fresnelDielectric(std::cos(theta), 1.0f, 1.5f);
  // u below F reflects, above refracts; the lobe probabilities are F and 1 - F.
  const BsdfSample r = sampleBsdf(g, wo, 0.5f * F, {0, 0});
  REQUIRE(r.wi.z == Approx(wo.z));
  REQUIRE(r.pdf == Approx(F));
  const BsdfSample t = sampleBsdf(g, wo, 0.5f + 0.5f * F, {0, 0});
  REQUIRE(t.wi.z < 0);
  REQUIRE(t.pdf == Approx(1 - F));
  const float sinT = std::sqrt(1 - t.wi.z * t.wi.z);
  REQUIRE(sinT * 1.5f == Approx(std::sin(theta)).epsilon(1e-5));  // Snell
  REQUIRE(t.weight.g == Approx(1 / (1.5f * 1.5f)));                  // radiance compression
  // Leaving the glass the way it came in restores the radiance: the weights multiply to 1.
  const BsdfSample back = sampleBsdf(g, t.wi, 0.999f, {0, 0});
  REQUIRE(back.wi.z > 0);
  REQUIRE(back.weight.g * t.weight.g == Approx(1.0f));
  REQUIRE(back.wi.x == Approx(wo.x).margin(1e-5));
  // Beyond the critical angle (asin(1/1.5) = 0.7297) inside the glass, everything reflects.
  const Vec3 inside = -directionAt(0.8f, 0.0f);
  REQUIRE(fresnelDielectric(std::cos(0.8f), 1.5f, 1.0f) == 1.0f);
  const BsdfSample tir = sampleBsdf(g, {-inside.x, -inside.y, inside.z}, 0.99f, {0, 0});
  REQUIRE(tir.wi.z < 0);
}

TEST_CASE("Phong lobes of huge exponents stay finite at the mirror direction", "[bsdf]") {
  // Exponents up to the loader's limit (1e15). At the mirror direction the lobe's cosine is 1, but
  // rounded it can exceed 1 by an ulp, and its power then overflowed: f and the pdf infinite, the
  // sample's weight NaN (a Phong Ns of 3e8 gave NaN pixels with pmfg).
  Rng rng(4);
  int aboveOne = 0;
  for (float ns : {3e8f, 1e12f, 1e15f}) {
    const SurfaceBsdf b = PhongLobe{Rgb(0.3f), Rgb(0.25f), ns};
    for (int i = 0; i < 20000; ++i) {
      const Vec3 wo = normalize(Vec3{rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() + 0.05f});
      const Vec3 mirror = reflect(wo, {0, 0, 1});
      aboveOne += dot(mirror, mirror) > 1.0f;
      const BsdfValue v = evalBsdfAndPdf(b, wo, mirror);
      INFO("Ns " << ns << ", wo " << wo.x << " " << wo.y << " " << wo.z);
      REQUIRE(isFinite(v.f));
      REQUIRE(std::isfinite(v.pdf));
      REQUIRE(v.pdf > 0);
      const BsdfSample s = sampleBsdf(b, wo, 0.99f, rng.uniform2());  // the Phong lobe
      if (s.valid) REQUIRE(isFinite(s.weight));
    }
  }
  CHECK(aboveOne > 100);  // the rounding the test is about did occur
}

TEST_CASE("lucent bsdf's directional albedo: the numerical integration's, kd, ks, and glass's Fresnel split",
          "[bsdf]") {
  // Sampled estimates (the command's) against independent values: the midpoint-rule integration of
  // test_bsdfs.h for Phong and glTF lobes, within 5 standard errors and the rule's 0.2%; constants
  // for the others, whose sample weights do not vary.
  Material gltf;
  gltf.type = MaterialType::Gltf;
  gltf.kd = Rgb(0.8f, 0.5f, 0.2f);
  gltf.ks = Rgb(1.0f);
  gltf.metallic = 0.3f;
  gltf.roughness = 0.4f;
  Material rough = gltf;
  rough.masking = GgxMasking::HeightCorrelated;
  rough.metallic = 0, rough.roughness = 0.8f;
  for (const SurfaceBsdf& b : {phong(0.4f, 0.5f, 40), materialBsdf(gltf), materialBsdf(rough)})
    for (const float cosTheta : {0.95f, 0.6f, 0.2f}) {
      const AlbedoEstimate e = directionalAlbedo(b, cosTheta, 200000, 3);
      const Rgb expected = test::directionalAlbedo(b, {std::sqrt(1 - cosTheta * cosTheta), 0, cosTheta});
      for (int c = 0; c < 3; ++c) {
        INFO("type " << int(b.type) << ", masking " << (b.type == MaterialType::Gltf ? int(b.gltf.masking) : -1) << ", cos theta " << cosTheta << ", channel " << c << ": " << e.albedo[c] << " +- "
                     << e.standardError[c] << " against " << expected[c]);
        CHECK(e.standardError[c] > 0);
        CHECK(std::abs(e.albedo[c] - expected[c]) <= 5 * e.standardError[c] + 0.002 * expected[c]);
      }
    }
  Material diffuse;
  diffuse.kd = Rgb(0.3f, 0.6f, 0.9f);
  const AlbedoEstimate lambert = directionalAlbedo(materialBsdf(diffuse), 0.5f, 1000, 1);
  for (int c = 0; c < 3; ++c) CHECK(lambert.albedo[c] == Approx(diffuse.kd[c]).epsilon(1e-6));
  CHECK(lambert.standardError.maxComponent() < 1e-6f);
  Material mirror;
  mirror.type = MaterialType::Mirror;
  mirror.ks = Rgb(0.9f, 0.8f, 0.7f);
  CHECK(directionalAlbedo(materialBsdf(mirror), 0.3f, 1000, 1).albedo == mirror.ks);
  // Glass from outside: reflected with weight 1 (probability F), refracted with radiance's
  // (1 / 1.5)^2; the mean F + (1 - F) / 2.25, within 5 standard errors.
  Material glass;
  glass.type = MaterialType::Glass;
  glass.ni = 1.5f;
  for (const float cosTheta : {0.9f, 0.2f}) {
    const AlbedoEstimate e = directionalAlbedo(materialBsdf(glass), cosTheta, 100000, 2);
    const double F = fresnelDielectric(cosTheta, 1.0f, 1.5f);
    INFO("cos theta " << cosTheta << ": " << e.albedo.g << " +- " << e.standardError.g);
    CHECK(std::abs(e.albedo.g - (F + (1 - F) / 2.25)) <= 5 * e.standardError.g);
  }
}

TEST_CASE("Every kind of the table keeps its flags' promises", "[bsdf]") {
  // For each row of bsdf/kinds.h, a material of that kind with coloured, non-trivial parameters:
  // specular lobes evaluate to nothing and sample deltas, others sample what they evaluate; a lobe
  // without transmission never sends light through, one with it does; a diffuse-only lobe's value
  // does not depend on the directions; the diffuse part, the albedo layer and the bound nest; a
  // two-sided lobe scatters only what arrives above it, another from both sides; a kind's name
  // leads back to it where scene files may give it.
  Material m;
  m.kd = Rgb(0.5f, 0.3f, 0.2f);
  m.ks = Rgb(0.3f, 0.4f, 0.2f);
  m.ns = 20;
  m.ni = 1.5f;
  m.metallic = 0.3f;
  m.roughness = 0.5f;
  std::vector<MaterialType> kinds;
#define LUCENT_TEST_KIND(kind, value, Lobe, member, name, sceneFile)                                        \
  kinds.push_back(MaterialType::kind);                                                                    \
  CHECK(uint32_t(MaterialType::kind) == value);                                                           \
  CHECK(std::string(materialTypeName(MaterialType::kind)) == name);                                       \
  CHECK(sceneFileMaterialType(name) == (sceneFile ? std::optional(MaterialType::kind) : std::nullopt));
  LUCENT_MATERIAL_KINDS(LUCENT_TEST_KIND)
#undef LUCENT_TEST_KIND
  // Every kind, and a glTF material that transmits (its lobe's flags depend on its parameters).
  std::vector<Material> materials;
  for (const MaterialType kind : kinds) {
    m.type = kind;
    materials.push_back(m);
  }
  materials.push_back(m);
  materials.back().type = MaterialType::Gltf;
  materials.back().transmission = 0.6f;
  Rng rng(12);
  for (const Material& material : materials) {
    const MaterialType kind = material.type;
    const SurfaceBsdf b = materialBsdf(material);
    const BsdfFlags flags = b.flags();
    INFO("kind " << materialTypeName(kind) << ", transmission " << material.transmission);
    REQUIRE(b.type == kind);
    CHECK((uint32_t(flags) & ~uint32_t(kindFlags(kind))) == 0);  // what the lobe does, its kind may
    CHECK(has(flags, BsdfFlags::Transmission) == (kind == MaterialType::Glass || material.transmission > 0));
    CHECK((has(flags, BsdfFlags::Reflection) || has(flags, BsdfFlags::Transmission)));
    CHECK((has(flags, BsdfFlags::Diffuse) || has(flags, BsdfFlags::Glossy) || has(flags, BsdfFlags::Specular)));
    const Rgb diffuse = b.diffuse(), albedo = layerAlbedo(b), bound = reflectanceBound(b);
    for (int c = 0; c < 3; ++c) {
      CHECK(diffuse[c] <= albedo[c]);
      CHECK(albedo[c] <= bound[c]);
    }
    CHECK(diffuse.isBlack() == !has(flags, BsdfFlags::Diffuse));
    int through = 0, back = 0;
    const BsdfValue reference = evalBsdfAndPdf(b, directionAt(0.3, 0.2), directionAt(0.9, 2.0));
    for (int i = 0; i < 2000; ++i) {
      const Vec3 wo = sampleUniformSphere(rng.uniform2());
      const Vec3 wi = sampleUniformSphere(rng.uniform2());
      const BsdfValue v = evalBsdfAndPdf(b, wo, wi);
      if (b.isDelta()) CHECK((v.f.isBlack() && v.pdf == 0));
      if (b.onlyDiffuse() && wo.z > 0 && wi.z > 0) CHECK(v.f == reference.f);
      // A two-sided lobe is only ever seen from above (the frame is turned to the viewer): from
      // below it scatters nothing. One that is not (glass) scatters light arriving from either side.
      const Vec3 woBelow{wo.x, wo.y, -std::abs(wo.z)};
      if (wo.z != 0)
        CHECK(sampleBsdf(b, woBelow, rng.uniform(), rng.uniform2()).valid == !has(flags, BsdfFlags::TwoSided));
      const BsdfSample s = sampleBsdf(b, wo, rng.uniform(), rng.uniform2());
      if (!s.valid) continue;
      CHECK(s.delta == b.isDelta());
      if (!s.delta) {
        const BsdfValue at = evalBsdfAndPdf(b, wo, s.wi);
        CHECK(s.pdf == Approx(at.pdf).epsilon(1e-5));
      }
      (s.wi.z * wo.z < 0 ? through : back) += 1;
    }
    CHECK((through > 0) == has(flags, BsdfFlags::Transmission));
    CHECK((back > 0) == has(flags, BsdfFlags::Reflection));
  }
}
