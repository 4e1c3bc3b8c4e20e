// A material's scattering at a surface point: one lobe of the kinds' table (bsdf/kinds.h), as a
// fixed plain record, and the one dispatch through which every method evaluates and samples it.
#pragma once
#include <algorithm>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>

#include "lucent/scene/bsdf/glass.h"
#include "lucent/scene/bsdf/gltf_metal_rough.h"
#include "lucent/scene/bsdf/kinds.h"
#include "lucent/scene/bsdf/lambertian.h"
#include "lucent/scene/bsdf/mirror.h"
#include "lucent/scene/bsdf/phong.h"
#include "lucent/scene/scene.h"

namespace lucent {

// The largest lobe's size in 4-byte words: SurfaceBsdf's union.
constexpr size_t kLargestLobeWords = std::max({
#define LUCENT_LOBE_WORDS(kind, value, Lobe, member, name, sceneFile) sizeof(Lobe) / 4,
    LUCENT_MATERIAL_KINDS(LUCENT_LOBE_WORDS)
#undef LUCENT_LOBE_WORDS
});

// The tag (the material's kind) and the lobe's parameters in a union as large as the largest lobe:
// the same size for every kind, so that dumps and GPU records hold any of them. The bytes a kind does not use are zero (the
// constructors clear them), so records compare and hash by their bytes.
struct SurfaceBsdf {
  MaterialType type = MaterialType::Diffuse;
  union {
#define LUCENT_LOBE_MEMBER(kind, value, Lobe, member, name, sceneFile) Lobe member;
    LUCENT_MATERIAL_KINDS(LUCENT_LOBE_MEMBER)
#undef LUCENT_LOBE_MEMBER
    uint32_t words_[kLargestLobeWords];  // all of the union, for clearing it
  };

  SurfaceBsdf() : SurfaceBsdf(LambertianLobe{}) {}
#define LUCENT_LOBE_CONSTRUCTOR(kind, value, Lobe, member, name, sceneFile) \
  SurfaceBsdf(const Lobe& lobe) : type(MaterialType::kind), words_{} { member = lobe; }
  LUCENT_MATERIAL_KINDS(LUCENT_LOBE_CONSTRUCTOR)
#undef LUCENT_LOBE_CONSTRUCTOR

  static constexpr size_t kLobeBytes = sizeof(words_);

  // Calls f with the lobe this record holds.
  template <class F>
  decltype(auto) visit(F&& f) const {
    switch (type) {
#define LUCENT_LOBE_CASE(kind, value, Lobe, member, name, sceneFile) \
  case MaterialType::kind: return f(member);
      LUCENT_MATERIAL_KINDS(LUCENT_LOBE_CASE)
#undef LUCENT_LOBE_CASE
    }
    return f(lambertian);
  }

  BsdfFlags flags() const;
  bool isDelta() const { return onlySpecular(flags()); }
  // Whether the photon methods pass the surface by a sample of its lobe, as they pass mirrors and
  // glass, instead of estimating there: specular lobes, and smooth ones that transmit (glTF glass
  // and shells of small roughness), under which an estimate from photons' directions is noise.
  bool passedAsSpecular() const;
  bool onlyDiffuse() const { return lucent::onlyDiffuse(flags()); }
  // Its Lambertian term's albedo: what the point-based methods and the diffuse estimates take.
  Rgb diffuse() const { return visit([](const auto& lobe) { return lobe.diffuse(); }); }

  // The lobe in a shading frame: its directions (a clear coat's normal), which bsdfAt gives in
  // world space, expressed in `frame`, turned to the frame's side. Every site that makes a frame to
  // evaluate or sample a lobe in takes the lobe through here (ChainVertex and ShadingPoint hold
  // theirs in their frames).
  SurfaceBsdf inFrame(const Frame& frame) const {
    return withCoatNormal([&](Vec3 n) { return frame.toLocal(n); });
  }
  // A lobe held in frame `from` expressed in frame `to` instead (about the same normal).
  SurfaceBsdf reframed(const Frame& from, const Frame& to) const {
    return withCoatNormal([&](Vec3 n) { return to.toLocal(from.toWorld(n)); });
  }

 private:
  template <class Map>
  SurfaceBsdf withCoatNormal(Map&& map) const {
    if (type != MaterialType::Gltf || !gltf.hasCoat()) return *this;
    SurfaceBsdf out = *this;
    const Vec3 n = map(gltf.coatNormal);
    out.gltf.coatNormal = n.z < 0 ? -n : n;
    return out;
  }
};
#define LUCENT_LOBE_FITS(kind, value, Lobe, member, name, sceneFile)                                     \
  static_assert(sizeof(Lobe) <= SurfaceBsdf::kLobeBytes && std::is_trivially_copyable_v<Lobe>, \
                #Lobe " fits SurfaceBsdf's union");
LUCENT_MATERIAL_KINDS(LUCENT_LOBE_FITS)
#undef LUCENT_LOBE_FITS
static_assert(sizeof(SurfaceBsdf) == 92 && std::is_trivially_copyable_v<SurfaceBsdf>,
              "SurfaceBsdf is a fixed plain record shared with dumps and GPU backends");

// What a kind's lobes may do: SurfaceBsdf::flags says what one does.
constexpr BsdfFlags kindFlags(MaterialType type) {
  switch (type) {
#define LUCENT_KIND_FLAGS(kind, value, Lobe, member, name, sceneFile) \
  case MaterialType::kind: return Lobe::flags;
    LUCENT_MATERIAL_KINDS(LUCENT_KIND_FLAGS)
#undef LUCENT_KIND_FLAGS
  }
  return BsdfFlags::None;
}

inline BsdfFlags SurfaceBsdf::flags() const {
  return visit([](const auto& lobe) { return instanceFlags(lobe); });
}
inline bool SurfaceBsdf::passedAsSpecular() const {
  const BsdfFlags f = flags();
  return onlySpecular(f) || (has(f, BsdfFlags::Specular) && has(f, BsdfFlags::Transmission));
}

// A kind's name, as scene files and `lucent bsdf` write it.
constexpr const char* materialTypeName(MaterialType type) {
  switch (type) {
#define LUCENT_KIND_NAME(kind, value, Lobe, member, name, sceneFile) \
  case MaterialType::kind: return name;
    LUCENT_MATERIAL_KINDS(LUCENT_KIND_NAME)
#undef LUCENT_KIND_NAME
  }
  return "?";
}

// The kind a scene file's material "type" names; none for a name no row lets a scene file give.
inline std::optional<MaterialType> sceneFileMaterialType(std::string_view name) {
#define LUCENT_SCENE_FILE_KIND(kind, value, Lobe, member, kindName, sceneFile) \
  if (sceneFile && name == kindName) return MaterialType::kind;
  LUCENT_MATERIAL_KINDS(LUCENT_SCENE_FILE_KIND)
#undef LUCENT_SCENE_FILE_KIND
  return std::nullopt;
}
// Those names, for messages: "diffuse, phong, mirror, glass".
inline std::string sceneFileMaterialTypes() {
  std::string out;
#define LUCENT_SCENE_FILE_NAME(kind, value, Lobe, member, name, sceneFile) \
  if (sceneFile) out += (out.empty() ? "" : ", ") + std::string(name);
  LUCENT_MATERIAL_KINDS(LUCENT_SCENE_FILE_NAME)
#undef LUCENT_SCENE_FILE_NAME
  return out;
}

// The reflectance a first hit records in the albedo layer: the diffuse and specular albedos (a
// glTF material's at normal incidence), a mirror's tint, 1 for glass.
inline Rgb layerAlbedo(const SurfaceBsdf& b) {
  return b.visit([](const auto& lobe) { return lobe.albedo(); });
}

// An upper bound of the light the surface reflects, per channel, for Russian roulette by
// reflectance.
inline Rgb reflectanceBound(const SurfaceBsdf& b) {
  return b.visit([](const auto& lobe) { return lobe.bound(); });
}

// The BSDF's value and the density with which sampleBsdf picks wi, computed together: zero for
// specular lobes (Dirac deltas), unless wo is above the surface (or below a lobe that keeps its
// inside: a volume's boundary), and unless wi is on wo's side or the lobe transmits.
inline BsdfValue evalBsdfAndPdf(const SurfaceBsdf& b, Vec3 wo, Vec3 wi) {
  const BsdfFlags flags = b.flags();
  const bool viewerSide = wo.z > 0 || (wo.z < 0 && !has(flags, BsdfFlags::TwoSided));
  const bool sameSide = wo.z > 0 ? wi.z > 0 : wi.z < 0, otherSide = wo.z > 0 ? wi.z < 0 : wi.z > 0;
  if (b.isDelta() || !viewerSide || !(sameSide || (otherSide && has(flags, BsdfFlags::Transmission))))
    return {Rgb(0.0f), 0.0f};
  return b.visit([&](const auto& lobe) { return lobe.evaluate(wo, wi); });
}
inline Rgb evalBsdf(const SurfaceBsdf& b, Vec3 wo, Vec3 wi) { return evalBsdfAndPdf(b, wo, wi).f; }
inline float bsdfPdf(const SurfaceBsdf& b, Vec3 wo, Vec3 wi) { return evalBsdfAndPdf(b, wo, wi).pdf; }

// The share of f(wo, wi) that is the Lambertian term's, per channel (0 where f is): how light
// scattered from wo to wi splits into diffuse and glossy reflection.
inline Rgb diffuseShare(const SurfaceBsdf& b, Vec3 wo, Vec3 wi) {
  return b.visit([&](const auto& lobe) { return lobe.diffuseShare(wo, wi); });
}

// Samples wi given wo; `u` picks the lobe's term, `u2` the direction.
inline BsdfSample sampleBsdf(const SurfaceBsdf& b, Vec3 wo, float u, Vec2 u2,
                             Transport transport = Transport::Radiance) {
  return b.visit([&](const auto& lobe) { return lobe.sample(wo, u, u2, transport); });
}

// Whether a surface's shading frame turns to the viewer on either side (every two-sided lobe) or
// keeps its winding's orientation (glass: its inside and outside differ).
inline bool twoSidedShading(const SurfaceBsdf& bsdf) { return has(bsdf.flags(), BsdfFlags::TwoSided); }

}  // namespace lucent
