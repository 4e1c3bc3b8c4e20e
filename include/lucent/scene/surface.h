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
inline Vec3 orientedShadingNormal(Vec3 interpolated, Vec3 ng) {
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
inline Vec3 shadingFrameNormal(Vec3 wo, Vec3 sn, Vec3 ng, bool twoSided) {
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
inline Vec3 bentForReflection(Vec3 wo, Vec3 n, Vec3 g) {
  const float z = dot(wo, g);
  const float t = std::min(0.9f * z, 0.01f);
  if (dot(reflect(wo, n), g) >= t) return n;
  const Vec3 tangential = n - g * dot(n, g);
  const float sinTilt = length(tangential);
  if (!(dot(n, g) > 0) || !(sinTilt > 0) || !(z > 0)) return g;
  const Vec3 X = tangential / sinTilt;
  const float x = dot(wo, X);
  const float rho = std::sqrt(x * x + z * z);
  const float theta = 0.5f * (std::atan2(x, z) + std::acos(std::min(1.0f, t / rho)));
  return normalize(X * std::sin(theta) + g * std::cos(theta));
}

// Texture t's coordinates at a surface point: its set's, interpolated, then transformed.
inline Vec2 textureUv(const Scene& scene, const Texture& t, const SurfacePoint& sp) {
  const std::vector<Vec2>& set = t.set == 0 ? scene.texcoords : scene.texcoords1;
  const uint32_t* v = &scene.indices[3 * sp.triangle];
  const Vec2 t0 = set[v[0]], t1 = set[v[1]], t2 = set[v[2]];
  const float b0 = 1.0f - sp.b1 - sp.b2;
  const Vec2 uv{t0.x * b0 + t1.x * sp.b1 + t2.x * sp.b2, t0.y * b0 + t1.y * sp.b1 + t2.y * sp.b2};
  return t.transformed == 0 ? uv : transformedUv(t.transform, uv);
}

// Texture `index` of the scene (>= 0) read at a surface point, bilinearly, decoded by `decode`.
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

// The radiance triangle tri emits at barycentrics (b1, b2) towards its front (front) or back side:
// the material's ke times its emissive texture; black towards the back unless the material emits
// there (Material::emitsBackFace).
inline Rgb emittedRadiance(const Scene& scene, uint32_t tri, float b1, float b2, bool front) {
  const Material& m = scene.materials[scene.materialIds[tri]];
  if (!front && m.emitsBackFace == 0) return Rgb(0.0f);
  if (m.emissiveTexture < 0) return m.ke;
  SurfacePoint sp;
  sp.triangle = tri, sp.b1 = b1, sp.b2 = b2;
  return m.ke * textureAt(scene, m.emissiveTexture, sp);
}

// glTF's normal texture at a hit: the texel's tangent-space normal (2 c - 1, x and y times the
// scale) in the frame of the unit normal n, the interpolated tangent made orthogonal to it, and the
// bitangent cross(n, t) * sign; n itself where the vertices have no tangent.
inline Vec3 normalMapped(const Scene& scene, const Material& m, const SurfacePoint& sp, Vec3 n) {
  const uint32_t* v = &scene.indices[3 * sp.triangle];
  const Tangent& a = scene.tangents[v[0]];
  Vec3 t = barycentric(a.direction, scene.tangents[v[1]].direction, scene.tangents[v[2]].direction, sp.b1, sp.b2);
  t = t - n * dot(n, t);
  const float len = length(t);
  if (!(len > 0)) return n;
  t = t / len;
  const Vec3 b = cross(n, t) * a.sign;
  const Rgb c = textureAt(scene, m.normalTexture, sp, kUnorm8ToFloat);
  const Vec3 p = t * ((2.0f * c.r - 1.0f) * m.normalScale) + b * ((2.0f * c.g - 1.0f) * m.normalScale) +
                 n * (2.0f * c.b - 1.0f);
  const float plen = length(p);
  return plen > 0 ? p / plen : n;
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
    const Vec3 n = vertexNormals ? barycentric(scene.normals[v[0]], scene.normals[v[1]], scene.normals[v[2]], b1, b2)
                                 : sp.geometricNormal;
    const float len = length(n);
    sp.shadingNormal = orientedShadingNormal(normalMapped(scene, m, sp, len > 0 ? n / len : sp.geometricNormal),
                                             sp.geometricNormal);
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

// Appendix B's metal/dielectric mix expanded into the lobe's terms (bsdf/gltf_metal_rough.h) for
// base colour `base`, from the file's factors times its textures: metallic and roughness, and
// KHR_materials_specular's specular factor and colour.
inline SurfaceBsdf gltfBsdf(const Material& m, Rgb base, float metallic, float roughness, float specular,
                            Rgb specularColour, Rgb sheenColour = Rgb(0.0f), float sheenRoughness = 0.0f) {
  GltfMetalRoughLobe b;
  // KHR_materials_ior and KHR_materials_specular: the dielectric's F0 from the index, coloured,
  // clamped to 1, then weighted by the specular factor, which is also its F90.
  const float r = (m.ni - 1.0f) / (m.ni + 1.0f);
  const Rgb c = specularColour;
  const Rgb f0 = Rgb(std::min(r * r * c.r, 1.0f), std::min(r * r * c.g, 1.0f), std::min(r * r * c.b, 1.0f)) * specular;
  b.kd = base * (1.0f - metallic);
  b.ks = f0 * (1.0f - metallic) + base * metallic;
  b.f90 = specular * (1.0f - metallic) + metallic;
  b.dielectricF0 = f0.maxComponent();
  b.dielectricF90 = specular;
  b.alpha = std::max(roughness * roughness, kMinGgxAlpha);
  b.masking = m.masking;
  if (!sheenColour.isBlack()) {
    b.sheenColour = sheenColour;
    b.sheenRoughness = std::max(sheenRoughness, kMinSheenRoughness);
  }
  return b;
}

// A material's lobe for diffuse colour kd (its Kd, or Kd times its texture and vertex colours), the
// other parameters from its factors.
inline SurfaceBsdf materialBsdf(const Material& m, Rgb kd) {
  switch (m.type) {
    case MaterialType::Diffuse: return LambertianLobe{kd};
    case MaterialType::Phong: return PhongLobe{kd, m.ks, m.ns};
    case MaterialType::Mirror: return MirrorLobe{m.ks};
    case MaterialType::Glass: return GlassLobe{m.ni};
    case MaterialType::Gltf:
      return gltfBsdf(m, kd, m.metallic, m.roughness, m.specular, m.ks, m.sheenColour, m.sheenRoughness);
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
         !scene.colours.empty();
}

// Texture `index`'s A channel (linear) at a surface point, filtered as its sampler says.
inline float textureAlphaAt(const Scene& scene, int32_t index, const SurfacePoint& sp) {
  const Texture& t = scene.textures[size_t(index)];
  return bilinearAlpha(bilinearFootprint(t, scene.texels.data(), textureUv(scene, t, sp)));
}

inline SurfaceBsdf bsdfAt(const Scene& scene, const SurfacePoint& sp) {
  const Material& m = scene.materials[sp.materialId];
  const Rgb factor = baseFactorAt(scene, m, sp);
  const Rgb kd = m.kdTexture < 0 ? factor : factor * textureAt(scene, m.kdTexture, sp);
  if (m.type == MaterialType::Gltf) {
    float metallic = m.metallic, roughness = m.roughness, specular = m.specular;
    Rgb specularColour = m.ks;
    if (m.metallicRoughnessTexture >= 0) {
      const Rgb t = textureAt(scene, m.metallicRoughnessTexture, sp, kUnorm8ToFloat);
      metallic *= t.b;
      roughness *= t.g;
    }
    if (m.specularTexture >= 0) specular *= textureAlphaAt(scene, m.specularTexture, sp);
    if (m.specularColorTexture >= 0) specularColour = specularColour * textureAt(scene, m.specularColorTexture, sp);
    Rgb sheenColour = m.sheenColour;
    float sheenRoughness = m.sheenRoughness;
    if (m.sheenColourTexture >= 0) sheenColour = sheenColour * textureAt(scene, m.sheenColourTexture, sp);
    if (m.sheenRoughnessTexture >= 0) sheenRoughness *= textureAlphaAt(scene, m.sheenRoughnessTexture, sp);
    return gltfBsdf(m, kd, metallic, roughness, specular, specularColour, sheenColour, sheenRoughness);
  }
  return materialBsdf(m, kd);
}

// Whether a scattered direction wi lies on the other side of the geometric surface (normal ng) than
// the lobe sampled says, wo being where the path came from: a reflection through the surface or a
// transmission that stays, which the shading normal allows and the real surface does not (a light
// leak). Such samples end the path.
inline bool leaksThroughSurface(Vec3 wo, Vec3 wi, Vec3 ng, bool transmits) {
  return (dot(wi, ng) * dot(wo, ng) < 0) != transmits;
}

// A hit as the specular chains of camera paths and gather rays see it: the surface and its BSDF,
// the direction back along the ray and which side of the winding it is on, and the shading frame
// (shadingFrameNormal) with that direction in it.
struct ChainVertex {
  SurfacePoint sp;
  SurfaceBsdf bsdf;
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
