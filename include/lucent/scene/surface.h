// The local geometry and material at a ray hit.
#pragma once
#include <optional>

#include "lucent/scene/bsdf.h"
#include "lucent/scene/scene.h"
#include "lucent/scene/texture.h"

namespace lucent {

struct SurfacePoint {
  Vec3 position;
  Vec3 geometricNormal;  // counter-clockwise winding normal (the emitting side)
  Vec3 shadingNormal;    // interpolated normal, on the same side as geometricNormal
  float b1 = 0, b2 = 0;  // barycentrics, for texture coordinates when a material needs them
  uint32_t triangle = 0;
  uint32_t materialId = 0;
};

// The functions below that take scalars are the path tracer's lane loop's too (shadeDiffuseLanes):
// written with selects only, so that the compiler vectorizes the very function the one-hit code
// calls, and the two compute the same IEEE operations.

// The vertex normals interpolated at a hit (not yet normalized), normalized and turned to the side
// of the geometric normal ng; ng itself where they cancel.
[[gnu::always_inline]] inline Vec3 orientedShadingNormal(Vec3 interpolated, Vec3 ng) {
  const float len = length(interpolated);
  const Vec3 n = select(len > 0, interpolated / len, ng);
  return select(dot(n, ng) < 0, -n, n);
}

// The geometric normal ng turned to the side of the shading normal n: directions below it meet the
// surface itself (gathering cuts them as the path tracer's leak test does).
inline Vec3 surfaceNormalOnSideOf(Vec3 ng, Vec3 n) { return dot(n, ng) < 0 ? -ng : ng; }

// The normal of a hit's shading frame, seen from wo: the shading normal sn, or the geometric normal
// ng where the two put the viewer on different sides (at silhouettes of smooth meshes); turned to
// the viewer's side for a two-sided material.
[[gnu::always_inline]] inline Vec3 shadingFrameNormal(Vec3 wo, Vec3 sn, Vec3 ng, bool twoSided) {
  const Vec3 n = select(dot(wo, sn) * dot(wo, ng) > 0, sn, ng);
  const bool behind = dot(wo, ng) > 0 ? false : twoSided;
  return select(behind, -n, n);
}

// A shading normal n (on wo's side) bent towards the geometric normal g (on wo's side) just enough
// that wo's mirror direction R stays above the surface: R.g >= t, t = min(0.9 wo.g, 0.01), so a
// reflection may be as shallow as the view (nearly) but no shallower than 0.01. Unchanged where R
// already is; g where n is not above the surface. This is the reflection correction production
// renderers apply to normal maps (Cycles'); derived here in the plane of g and n's tangential part
// X: with n(theta) = sin(theta) X + cos(theta) g and wo = (x, ., z) in (X, g),
//   R(theta).g = 2 (n.wo)(n.g) - z = x sin(2 theta) + z cos(2 theta) = rho cos(2 theta - phi),
// rho = |(x, z)|, phi = atan2(x, z). R.g >= t where |2 theta - phi| <= acos(t / rho), an interval
// holding theta = 0 (R.g = z > t there); the tilt kept is its upper end, the nearest to n's.
// reflectsTooLow: whether n needs bending (R.g < t), with selects only (the path tracer's lanes
// test it for every glTF hit and bend the few that need it one at a time).
[[gnu::always_inline]] inline bool reflectsTooLow(Vec3 wo, Vec3 n, Vec3 g) {
  return !(dot(reflect(wo, n), g) >= std::min(0.9f * dot(wo, g), 0.01f));
}
inline Vec3 bentForReflection(Vec3 wo, Vec3 n, Vec3 g) {
  if (!reflectsTooLow(wo, n, g)) return n;
  const float z = dot(wo, g);
  const float t = std::min(0.9f * z, 0.01f);
  const Vec3 tangential = n - g * dot(n, g);
  const float sinTilt = length(tangential);
  if (!(dot(n, g) > 0) || !(sinTilt > 0) || !(z > 0)) return g;
  const Vec3 X = tangential / sinTilt;
  const float x = dot(wo, X);
  const float rho = std::sqrt(x * x + z * z);
  const float theta = 0.5f * (std::atan2(x, z) + std::acos(std::min(1.0f, t / rho)));
  return normalize(X * std::sin(theta) + g * std::cos(theta));
}

// A set of texture coordinates (Scene::texcoords or texcoords1) interpolated at a surface point.
inline Vec2 interpolatedUv(const Scene& scene, uint32_t set, const SurfacePoint& sp) {
  const std::vector<Vec2>& uvs = set == 0 ? scene.texcoords : scene.texcoords1;
  const uint32_t* v = &scene.indices[3 * sp.triangle];
  const Vec2 t0 = uvs[v[0]], t1 = uvs[v[1]], t2 = uvs[v[2]];
  const float b0 = 1.0f - sp.b1 - sp.b2;
  return {t0.x * b0 + t1.x * sp.b1 + t2.x * sp.b2, t0.y * b0 + t1.y * sp.b1 + t2.y * sp.b2};
}

// A hit's texture coordinates, interpolated once for all the textures its material reads: the
// first set's, and the second's where the scene has one.
struct HitUv {
  Vec2 set[2];
};
inline HitUv hitUv(const Scene& scene, const SurfacePoint& sp) {
  HitUv uv;
  if (!scene.texcoords.empty()) uv.set[0] = interpolatedUv(scene, 0, sp);
  if (!scene.texcoords1.empty()) uv.set[1] = interpolatedUv(scene, 1, sp);
  return uv;
}

// Texture t's coordinates at a hit: its set's, transformed.
inline Vec2 textureUv(const Texture& t, const HitUv& uv) {
  return t.transformed == 0 ? uv.set[t.set] : transformedUv(t.transform, uv.set[t.set]);
}
inline Vec2 textureUv(const Scene& scene, const Texture& t, const SurfacePoint& sp) {
  const Vec2 uv = interpolatedUv(scene, t.set, sp);
  return t.transformed == 0 ? uv : transformedUv(t.transform, uv);
}

// Texture `index` of the scene (>= 0) read at a hit's coordinates, bilinearly, decoded by `decode`.
inline Rgb textureAt(const Scene& scene, int32_t index, const HitUv& uv,
                     const std::array<float, 256>& decode = kSrgb8ToLinear) {
  const Texture& t = scene.textures[size_t(index)];
  return bilinear(bilinearFootprint(t, scene.texels.data(), textureUv(t, uv)), decode);
}
inline Rgb textureAt(const Scene& scene, int32_t index, const SurfacePoint& sp,
                     const std::array<float, 256>& decode = kSrgb8ToLinear) {
  const Texture& t = scene.textures[size_t(index)];
  return bilinear(bilinearFootprint(t, scene.texels.data(), textureUv(scene, t, sp)), decode);
}

// glTF's COLOR_0 interpolated at a surface point; white and opaque where the scene has none.
inline VertexColour vertexColourAt(const Scene& scene, const SurfacePoint& sp) {
  if (scene.colours.empty()) return {};
  const uint32_t* v = &scene.indices[3 * sp.triangle];
  const VertexColour a = scene.colours[v[0]], b = scene.colours[v[1]], c = scene.colours[v[2]];
  const float b0 = 1.0f - sp.b1 - sp.b2;
  return {a.rgb * b0 + b.rgb * sp.b1 + c.rgb * sp.b2, a.alpha * b0 + b.alpha * sp.b1 + c.alpha * sp.b2};
}

// The material's base colour factor at a surface point: its kd times the vertex colour, where the
// scene has vertex colours (glTF's COLOR_0); a colour texture multiplies it in turn.
inline Rgb baseFactorAt(const Scene& scene, const Material& m, const SurfacePoint& sp) {
  return scene.colours.empty() ? m.kd : m.kd * vertexColourAt(scene, sp).rgb;
}

// A normal texture's texel c (linear), x and y times `scale`, in the frame of the unit normal n and
// the interpolated tangent t: t made orthogonal to n, the bitangent cross(n, t) * sign; n where t
// lies along n. Selects only, for the path tracer's lane loop (shadeGltfLanes) too.
[[gnu::always_inline]] inline Vec3 tangentSpaceNormal(Vec3 n, Vec3 t, float sign, Rgb c, float scale) {
  t = t - n * dot(n, t);
  const float len = length(t);
  t = t / len;
  const Vec3 b = cross(n, t) * sign;
  const Vec3 p = t * ((2.0f * c.r - 1.0f) * scale) + b * ((2.0f * c.g - 1.0f) * scale) + n * (2.0f * c.b - 1.0f);
  const float plen = length(p);
  return select(len > 0 ? plen > 0 : false, p / plen, n);
}

// A glTF normal texture (its index and scale) at a hit: its texel's tangentSpaceNormal about the unit
// normal n and the vertices' tangents interpolated.
inline Vec3 normalMapped(const Scene& scene, int32_t texture, float scale, const SurfacePoint& sp, Vec3 n) {
  const uint32_t* v = &scene.indices[3 * sp.triangle];
  const Tangent& a = scene.tangents[v[0]];
  const Vec3 t = barycentric(a.direction, scene.tangents[v[1]].direction, scene.tangents[v[2]].direction, sp.b1, sp.b2);
  return tangentSpaceNormal(n, t, a.sign, textureAt(scene, texture, sp, kUnorm8ToFloat), scale);
}

// The unit vertex normal interpolated at a hit, as the vertices give it (not turned to a side); the
// geometric normal where the face has no vertex normals (OBJ faces have them at all their vertices
// or at none, stored as zero) or where they cancel.
inline Vec3 interpolatedNormal(const Scene& scene, const SurfacePoint& sp) {
  const uint32_t* v = &scene.indices[3 * sp.triangle];
  if (scene.normals[v[0]] == Vec3{0, 0, 0}) return sp.geometricNormal;
  const Vec3 n = barycentric(scene.normals[v[0]], scene.normals[v[1]], scene.normals[v[2]], sp.b1, sp.b2);
  const float len = length(n);
  return len > 0 ? n / len : sp.geometricNormal;
}

inline SurfacePoint surfaceAt(const Scene& scene, uint32_t tri, float b1, float b2) {
  SurfacePoint sp;
  sp.triangle = tri;
  sp.materialId = scene.materialIds[tri];
  sp.b1 = b1;
  sp.b2 = b2;
  const uint32_t* v = &scene.indices[3 * tri];
  sp.position = barycentric(scene.positions[v[0]], scene.positions[v[1]], scene.positions[v[2]], b1, b2);
  sp.geometricNormal = scene.geometricNormal(tri);
  sp.shadingNormal = sp.geometricNormal;
  // OBJ faces have normals at all their vertices or at none (then they are stored as zero).
  const bool vertexNormals = !(scene.normals[v[0]] == Vec3{0, 0, 0});
  const Material& m = scene.materials[sp.materialId];
  if (m.normalTexture >= 0) {
    sp.shadingNormal = orientedShadingNormal(
        normalMapped(scene, m.normalTexture, m.normalScale, sp, interpolatedNormal(scene, sp)), sp.geometricNormal);
  } else if (vertexNormals) {
    const Vec3 n = barycentric(scene.normals[v[0]], scene.normals[v[1]], scene.normals[v[2]], b1, b2);
    sp.shadingNormal = orientedShadingNormal(n, sp.geometricNormal);
  }
  return sp;
}

// The smallest GGX alpha rendered (roughness 0.0316): below it the lobe's peak, 1 / (pi alpha^2),
// outgrows what float sampling weights resolve; a smoother glTF surface is listed in the ignored
// content when its factor asks for one.
constexpr float kMinGgxAlpha = 1e-3f;

// KHR_materials_clearcoat's normal at a hit, in world space on the geometric normal's side: its own
// normal texture's, else the interpolated vertex normal (the extension maps the coat only by its
// own texture, even where the base has one).
inline Vec3 clearcoatNormalAt(const Scene& scene, const Material& m, const SurfacePoint& sp) {
  if (m.normalTexture < 0 && m.clearcoatNormalTexture < 0) return sp.shadingNormal;
  const Vec3 n = interpolatedNormal(scene, sp);
  if (m.clearcoatNormalTexture < 0) return orientedShadingNormal(n, sp.geometricNormal);
  return orientedShadingNormal(normalMapped(scene, m.clearcoatNormalTexture, m.clearcoatNormalScale, sp, n),
                               sp.geometricNormal);
}

// A glTF material's factors at a surface point: the file's factors times its textures (bsdfAt), or
// the factors alone (gltfFactors).
struct GltfFactors {
  Rgb base;  // base colour (times vertex colours)
  float metallic = 0, roughness = 1;
  float specular = 1;  // KHR_materials_specular's factor and colour
  Rgb specularColour{1.0f};
  Rgb sheenColour{0.0f};  // KHR_materials_sheen's
  float sheenRoughness = 0;
  float clearcoat = 0, clearcoatRoughness = 0;  // KHR_materials_clearcoat's
  Vec3 clearcoatNormal{0, 0, 1};                // in world space; the shading normal's in gltfFactors
  float transmission = 0;                       // KHR_materials_transmission's
};

// The material's factors, its base colour `base`.
inline GltfFactors gltfFactors(const Material& m, Rgb base) {
  GltfFactors f;
  f.base = base;
  f.metallic = m.metallic, f.roughness = m.roughness;
  f.specular = m.specular, f.specularColour = m.ks;
  f.sheenColour = m.sheenColour, f.sheenRoughness = m.sheenRoughness;
  f.clearcoat = m.clearcoat, f.clearcoatRoughness = m.clearcoatRoughness;
  f.transmission = m.transmission;
  return f;
}

// KHR_materials_ior and KHR_materials_specular: the dielectric's F0 from the index ni, coloured,
// clamped to 1, then weighted by the specular factor (which is also its F90).
inline Rgb dielectricF0(float ni, Rgb specularColour, float specular) {
  const float r = (ni - 1.0f) / (ni + 1.0f);
  const Rgb c = specularColour;
  return Rgb(std::min(r * r * c.r, 1.0f), std::min(r * r * c.g, 1.0f), std::min(r * r * c.b, 1.0f)) * specular;
}

// Appendix B's metal/dielectric mix of base colour `base` and dielectric F0 f0 (dielectricF0) and
// F90 `specular`, as the lobe's terms: the base of every glTF lobe (gltfBsdf), and of the path
// tracer's lanes (shadeGltfLanes).
[[gnu::always_inline]]
inline GltfMetalRoughLobe metalRoughLobe(Rgb base, float metallic, float roughness, Rgb f0, float specular,
                                         GgxMasking masking) {
  GltfMetalRoughLobe b;
  b.kd = base * (1.0f - metallic);
  b.ks = f0 * (1.0f - metallic) + base * metallic;
  b.f90 = specular * (1.0f - metallic) + metallic;
  b.dielectricF0 = f0.maxComponent();
  b.dielectricF90 = specular;
  b.alpha = std::max(roughness * roughness, kMinGgxAlpha);
  b.masking = masking;
  return b;
}

// Appendix B's metal/dielectric mix expanded into the lobe's terms (bsdf/gltf_metal_rough.h), with
// the transmission, sheen and clear coat where the factors have them.
inline SurfaceBsdf gltfBsdf(const Material& m, const GltfFactors& f) {
  GltfMetalRoughLobe b = metalRoughLobe(f.base, f.metallic, f.roughness,
                                        dielectricF0(m.ni, f.specularColour, f.specular), f.specular, m.masking);
  if (!f.sheenColour.isBlack()) {
    b.sheenColour = f.sheenColour;
    b.sheenRoughness = std::max(f.sheenRoughness, kMinSheenRoughness);
  }
  if (f.clearcoat > 0) {
    b.coat = f.clearcoat;
    b.coatAlpha = std::max(f.clearcoatRoughness * f.clearcoatRoughness, kMinGgxAlpha);
    b.coatNormal = f.clearcoatNormal;
  }
  b.transmission = f.transmission;
  if (m.boundsVolume) b.volumeIor = m.ni;
  return b;
}

// What light keeps of itself crossing a length x of the medium material m bounds (Beer-Lambert,
// KHR_materials_volume): attenuationColour^(x / attenuationDistance) per channel, 1 with no
// attenuation, 0 over an infinite length with some.
inline Rgb mediumTransmittance(const Material& m, float x) {
  Rgb t(1.0f);
  if (!(m.attenuationDistance < kInf)) return t;
  for (int c = 0; c < 3; ++c)
    if (m.attenuationColour[c] < 1.0f) t[c] = std::pow(m.attenuationColour[c], x / m.attenuationDistance);
  return t;
}

// A material's lobe for diffuse colour kd (its Kd, or Kd times its texture and vertex colours), the
// other parameters from its factors; a clear coat's normal is the shading normal (+z of the frame).
inline SurfaceBsdf materialBsdf(const Material& m, Rgb kd) {
  switch (m.type) {
    case MaterialType::Diffuse: return LambertianLobe{kd};
    case MaterialType::Phong: return PhongLobe{kd, m.ks, m.ns};
    case MaterialType::Mirror: return MirrorLobe{m.ks};
    case MaterialType::Glass: return GlassLobe{m.ni};
    case MaterialType::Gltf: return gltfBsdf(m, gltfFactors(m, kd));
  }
  return LambertianLobe{kd};
}
// A material's BSDF from its factors alone, as bsdfAt gives it where no texture or vertex colour
// scales them.
inline SurfaceBsdf materialBsdf(const Material& m) { return materialBsdf(m, m.kd); }

// Whether bsdfAt's lobe for the material varies over the surface: a texture or vertex colours
// scale its factors (where not, materialBsdf(m) is the lobe everywhere).
inline bool lobeVariesOverSurface(const Scene& scene, const Material& m) {
  return m.kdTexture >= 0 || m.metallicRoughnessTexture >= 0 || m.specularTexture >= 0 ||
         m.specularColorTexture >= 0 || m.sheenColourTexture >= 0 || m.sheenRoughnessTexture >= 0 ||
         m.clearcoatTexture >= 0 || m.clearcoatRoughnessTexture >= 0 || m.transmissionTexture >= 0 ||
         !scene.colours.empty();
}

// Whether bsdfAt's lobe for the material is passed as specular (SurfaceBsdf::passedAsSpecular)
// anywhere on its surface: its factors' lobe is, or a transmitter's roughness texture may make it
// so (the texture scales the roughness factor down).
inline bool mayPassAsSpecular(const Material& m) {
  return materialBsdf(m).passedAsSpecular() ||
         (m.type == MaterialType::Gltf && m.metallicRoughnessTexture >= 0 && (m.transmission > 0 || m.boundsVolume));
}

// Texture `index`'s A channel (linear) at a hit's coordinates, filtered as its sampler says.
inline float textureAlphaAt(const Scene& scene, int32_t index, const HitUv& uv) {
  const Texture& t = scene.textures[size_t(index)];
  return bilinearAlpha(bilinearFootprint(t, scene.texels.data(), textureUv(t, uv)));
}

inline SurfaceBsdf bsdfAt(const Scene& scene, const SurfacePoint& sp) {
  const Material& m = scene.materials[sp.materialId];
  const Rgb factor = baseFactorAt(scene, m, sp);
  if (m.type != MaterialType::Gltf)
    return materialBsdf(m, m.kdTexture < 0 ? factor : factor * textureAt(scene, m.kdTexture, sp));
  const HitUv uv = hitUv(scene, sp);
  GltfFactors f = gltfFactors(m, m.kdTexture < 0 ? factor : factor * textureAt(scene, m.kdTexture, uv));
  if (m.metallicRoughnessTexture >= 0) {
    const Rgb t = textureAt(scene, m.metallicRoughnessTexture, uv, kUnorm8ToFloat);
    f.metallic *= t.b;
    f.roughness *= t.g;
  }
  if (m.specularTexture >= 0) f.specular *= textureAlphaAt(scene, m.specularTexture, uv);
  if (m.specularColorTexture >= 0) f.specularColour = f.specularColour * textureAt(scene, m.specularColorTexture, uv);
  if (m.sheenColourTexture >= 0) f.sheenColour = f.sheenColour * textureAt(scene, m.sheenColourTexture, uv);
  if (m.sheenRoughnessTexture >= 0) f.sheenRoughness *= textureAlphaAt(scene, m.sheenRoughnessTexture, uv);
  if (m.clearcoat > 0) {
    if (m.clearcoatTexture >= 0) f.clearcoat *= textureAt(scene, m.clearcoatTexture, uv, kUnorm8ToFloat).r;
    if (m.clearcoatRoughnessTexture >= 0)
      f.clearcoatRoughness *= textureAt(scene, m.clearcoatRoughnessTexture, uv, kUnorm8ToFloat).g;
    f.clearcoatNormal = clearcoatNormalAt(scene, m, sp);
  }
  if (m.transmissionTexture >= 0) f.transmission *= textureAt(scene, m.transmissionTexture, uv, kUnorm8ToFloat).r;
  return gltfBsdf(m, f);
}

// The radiance triangle tri emits at barycentrics (b1, b2) along direction `towards` (leaving the
// surface): the material's ke times its emissive texture, black behind its front (the side of its
// winding normal) unless the material emits there (Material::emitsBackFace); under a clear coat,
// what the coat lets through, 1 - Wc(towards) (KHR_materials_clearcoat: emission lies beneath it).
inline Rgb emittedRadiance(const Scene& scene, uint32_t tri, float b1, float b2, Vec3 towards) {
  const Material& m = scene.materials[scene.materialIds[tri]];
  if (!(dot(towards, scene.geometricNormal(tri)) > 0) && m.emitsBackFace == 0) return Rgb(0.0f);
  if (m.emissiveTexture < 0 && !(m.clearcoat > 0)) return m.ke;
  // The texture reads the barycentrics alone; the coat needs the whole surface point (its normals).
  SurfacePoint sp;
  sp.triangle = tri, sp.b1 = b1, sp.b2 = b2;
  const Rgb le = m.emissiveTexture < 0 ? m.ke : m.ke * textureAt(scene, m.emissiveTexture, sp);
  if (!(m.clearcoat > 0)) return le;
  const SurfaceBsdf bsdf = bsdfAt(scene, surfaceAt(scene, tri, b1, b2));
  return bsdf.type == MaterialType::Gltf ? le * (1.0f - bsdf.gltf.coatWeight(towards)) : le;
}

// The medium a ray leaving a point of material `materialId` (geometric normal ng, lobe bsdf) along
// d travels in, as an index into Scene::materials, kNoMedium for none: where the lobe keeps an
// inside (a volume's boundary, glass) the material's if d goes in (none for a material that does
// not attenuate: only media that do are followed) and none if it goes out (media do not nest),
// `current` if it goes out of one that does not attenuate (a reflection off glass in water stays
// in the water); elsewhere `current`, the medium the path arrived in.
inline uint32_t mediumTowards(const Scene& scene, uint32_t materialId, Vec3 ng, const SurfaceBsdf& bsdf, Vec3 d,
                              uint32_t current) {
  const BsdfFlags flags = bsdf.flags();
  if (!has(flags, BsdfFlags::Transmission) || has(flags, BsdfFlags::TwoSided)) return current;
  const bool in = dot(d, ng) < 0;
  if (!(scene.materials[materialId].attenuationDistance < kInf)) return in ? kNoMedium : current;
  return in ? materialId : kNoMedium;
}
inline uint32_t mediumTowards(const Scene& scene, const SurfacePoint& sp, const SurfaceBsdf& bsdf, Vec3 d,
                              uint32_t current) {
  return mediumTowards(scene, sp.materialId, sp.geometricNormal, bsdf, d, current);
}

// What light keeps of itself along a segment of length x in `medium` (kNoMedium: all of it).
inline Rgb transmittanceIn(const Scene& scene, uint32_t medium, float x) {
  return medium == kNoMedium ? Rgb(1.0f) : mediumTransmittance(scene.materials[medium], x);
}

// Whether a scattered direction wi lies on the other side of the geometric surface (normal ng) than
// the lobe sampled says, wo being where the path came from: a reflection through the surface or a
// transmission that stays, which the shading normal allows and the real surface does not (a light
// leak). Such samples end the path.
inline bool leaksThroughSurface(Vec3 wo, Vec3 wi, Vec3 ng, bool transmits) {
  return (dot(wi, ng) * dot(wo, ng) < 0) != transmits;
}

// The cosine at which a lobe receives light arriving from direction wi (wiLocal in its frame of
// normal n, ng the geometric normal): wiLocal.z where wi lies above both the shading and the real
// surface, -wiLocal.z below both for a lobe that transmits, else 0 (the other side, or a leak past
// the shading normal). Written with selects for the path tracer's lane loop.
inline float receivingCosine(Vec3 wi, Vec3 wiLocal, Vec3 n, Vec3 ng, bool transmits) {
  const float turn = transmits && wiLocal.z < 0 ? -1.0f : 1.0f;
  const float cosine = wiLocal.z * turn;
  const float side = dot(wi, ng) * dot(n, ng) * turn;
  return side > 0 ? cosine : 0.0f;
}

// A hit as the specular chains of camera paths and gather rays see it: the surface and its BSDF,
// the direction back along the ray and which side of the winding it is on, and the shading frame
// (shadingFrameNormal) with that direction in it.
struct ChainVertex {
  SurfacePoint sp;
  SurfaceBsdf bsdf;  // in `frame`
  Vec3 wo;
  bool frontFace = false;
  Frame frame;
  Vec3 woLocal;
};

// The normal of a hit's shading frame seen from wo (shadingFrameNormal), a normal map's bent where
// its material asks (Material::bendsNormalMap, bentForReflection).
inline Vec3 hitFrameNormal(const Scene& scene, const SurfacePoint& sp, Vec3 wo, bool twoSided) {
  const Vec3 n = shadingFrameNormal(wo, sp.shadingNormal, sp.geometricNormal, twoSided);
  const Material& m = scene.materials[sp.materialId];
  if (m.bendsNormalMap == 0 || !(dot(wo, n) > 0)) return n;
  return bentForReflection(wo, n, dot(wo, sp.geometricNormal) > 0 ? sp.geometricNormal : -sp.geometricNormal);
}

inline ChainVertex chainVertexAt(const Scene& scene, const SurfacePoint& sp, Vec3 rayDirection) {
  ChainVertex v;
  v.sp = sp;
  v.bsdf = bsdfAt(scene, sp);
  v.wo = -rayDirection;
  v.frontFace = dot(v.wo, sp.geometricNormal) > 0;
  v.frame = Frame(hitFrameNormal(scene, sp, v.wo, twoSidedShading(v.bsdf)));
  v.bsdf = v.bsdf.inFrame(v.frame);
  v.woLocal = v.frame.toLocal(v.wo);
  return v;
}

// The ray that follows a lobe sample from a chain vertex, offset off its surface; none where the
// sample is invalid or would leak through the real surface (leaksThroughSurface).
inline std::optional<Ray> followLobe(const ChainVertex& v, const BsdfSample& s) {
  if (!s.valid) return std::nullopt;
  const Vec3 wi = v.frame.toWorld(s.wi);
  if (leaksThroughSurface(v.wo, wi, v.sp.geometricNormal, s.wi.z * v.woLocal.z < 0)) return std::nullopt;
  return Ray{offsetOrigin(v.sp.position, v.sp.geometricNormal, wi), wi};
}

}  // namespace lucent
