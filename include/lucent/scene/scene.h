// The loaded scene: flat arrays of plain data, indices instead of pointers (DESIGN.md "Data model").
#pragma once
#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "lucent/core/distribution.h"
#include "lucent/core/math.h"
#include "lucent/image/image.h"
#include "lucent/scene/bsdf/kinds.h"
#include "lucent/scene/ggx.h"

namespace lucent {

// What a material is: a row of the kinds' table (bsdf/kinds.h), its lobe in bsdf/.
enum class MaterialType : uint32_t {
#define LUCENT_MATERIAL_TYPE(kind, value, Lobe, member, name, sceneFile) kind = value,
  LUCENT_MATERIAL_KINDS(LUCENT_MATERIAL_TYPE)
#undef LUCENT_MATERIAL_TYPE
};

// glTF's alphaMode: opaque; masked (a point is there where its alpha is at least alphaCutoff); or
// blended, rendered as stochastic transparency (a point is there with probability alpha).
enum class AlphaMode : uint32_t { Opaque = 0, Mask = 1, Blend = 2 };

// Lambertian Kd (optionally textured) plus a normalized Phong lobe Ks (n+2)/(2 pi) cos^Ns;
// mirror reflects with tint Ks; glass is a smooth dielectric of index Ni. Ke is emission on the side
// of the counter-clockwise winding normal (both sides where emitsBackFace is 1), times the
// emissiveTexture.
// A glTF material keeps its parameters as the file gives them: Kd the base colour factor (times
// the kdTexture), Ks the specular colour factor (KHR_materials_specular), Ni the index of refraction
// (KHR_materials_ior), and the fields below; bsdfAt turns them into Appendix B's lobes.
struct Material {
  MaterialType type = MaterialType::Diffuse;
  Rgb kd{0.5f};
  Rgb ks{0.0f};
  float ns = 1.0f;
  float ni = 1.5f;
  Rgb ke{0.0f};
  int32_t kdTexture = -1;  // index into Scene::textures, -1 for none
  // glTF only.
  float metallic = 0.0f, roughness = 1.0f;
  GgxMasking masking = GgxMasking::Separable;  // Smith's form (ggx.h): --gltf-masking's
  float specular = 1.0f;                   // KHR_materials_specular's specularFactor
  int32_t metallicRoughnessTexture = -1;   // linear; B scales metallic, G roughness
  int32_t normalTexture = -1;              // linear tangent-space normals, x and y scaled by normalScale
  float normalScale = 1.0f;
  // Where the surface is (every visibility query, Visibility's filter): alpha = baseAlpha times the
  // kdTexture's A channel (linear).
  AlphaMode alphaMode = AlphaMode::Opaque;
  float alphaCutoff = 0.5f, baseAlpha = 1.0f;
  // Emission: ke times this texture (sRGB), from the front face, and from the back face too where
  // emitsBackFace is 1 (glTF's doubleSided).
  int32_t emissiveTexture = -1;
  uint32_t emitsBackFace = 0;
  // glTF's doubleSided false: seen by the camera from behind (against the counter-clockwise winding
  // normal) the surface is not there (Visibility's filter, RayKind::Camera); every other ray meets
  // both sides.
  uint32_t culledBehind = 0;
  // 1: the normal texture's shading normal is bent towards the geometric one, per viewing
  // direction, so that the mirror direction stays above the surface (bentForReflection,
  // surface.h); 0: as the texture gives it.
  uint32_t bendsNormalMap = 0;
  // KHR_materials_sheen: the sheen colour, times sheenColourTexture's RGB (sRGB), and roughness,
  // times sheenRoughnessTexture's A (linear); black: no sheen layer (bsdf/sheen.h).
  Rgb sheenColour{0.0f};
  float sheenRoughness = 0.0f;
  int32_t sheenColourTexture = -1, sheenRoughnessTexture = -1;
  // KHR_materials_specular's textures: A (linear) times `specular`, RGB (sRGB) times ks.
  int32_t specularTexture = -1, specularColorTexture = -1;
  // KHR_materials_clearcoat: the coat's weight, times clearcoatTexture's R, and roughness, times
  // clearcoatRoughnessTexture's G; its normal texture, x and y scaled by clearcoatNormalScale (all
  // linear); 0: no coat (bsdf/gltf_metal_rough.h).
  float clearcoat = 0.0f, clearcoatRoughness = 0.0f;
  int32_t clearcoatTexture = -1, clearcoatRoughnessTexture = -1, clearcoatNormalTexture = -1;
  float clearcoatNormalScale = 1.0f;
  // KHR_materials_transmission (thin-walled): the share of the diffuse base that passes through,
  // times transmissionTexture's R (linear); 0: opaque.
  float transmission = 0.0f;
  int32_t transmissionTexture = -1;
  // KHR_materials_volume (thicknessFactor > 0): 1 where the mesh bounds a medium of index ni on its
  // winding's inside, which light crossing a length x keeps attenuationColour^(x /
  // attenuationDistance) of (Beer-Lambert; +inf: none; mediumTransmittance).
  uint32_t boundsVolume = 0;
  Rgb attenuationColour{1.0f};
  float attenuationDistance = kInf;
};
static_assert(sizeof(Material) == 192, "Material is a fixed-size record shared with GPU backends");
// A medium is named by the index of the material bounding it (a KHR_materials_volume boundary that
// attenuates); kNoMedium: none (mediumTowards).
constexpr uint32_t kNoMedium = ~0u;

// A texture stored in Scene::texels from `offset`, row-major, row 0 at the top (v = 1). Texels are
// 8-bit RGBA packed in 32 bits (R in the low byte), sRGB-encoded for colour (kdTexture) and linear
// for data (metallicRoughnessTexture): reflectances lie in [0, 1], the scenes' textures are 8-bit,
// and a third of the float size keeps lookups in cache.
// How coordinates outside [0, 1] and between texels read a texture (glTF's samplers; MTL maps
// repeat and filter bilinearly).
enum class TextureWrap : uint32_t { Repeat = 0, Clamp = 1, Mirror = 2 };
// A texture reads the vertices' texture coordinates of its set (Scene::texcoords or texcoords1),
// transformed where `transformed` is 1 (glTF's KHR_texture_transform, in Lucent's coordinates):
// u' = transform[0] u + transform[1] v + transform[2], v' = transform[3] u + transform[4] v + transform[5].
struct Texture {
  uint32_t offset = 0;
  uint32_t width = 0, height = 0;
  TextureWrap wrapU = TextureWrap::Repeat, wrapV = TextureWrap::Repeat;  // along u (image x) and v (image y)
  uint32_t nearest = 0;  // 1: the nearest texel, not a bilinear blend
  uint32_t set = 0;      // 0: Scene::texcoords, 1: Scene::texcoords1
  uint32_t transformed = 0;
  float transform[6] = {1, 0, 0, 0, 1, 0};
};
static_assert(sizeof(Texture) == 56, "Texture is a fixed-size record shared with GPU backends");

// Texture coordinates uv moved by a Texture::transform m.
inline Vec2 transformedUv(const float* m, Vec2 uv) {
  return {m[0] * uv.x + m[1] * uv.y + m[2], m[3] * uv.x + m[4] * uv.y + m[5]};
}

enum class LightType : uint32_t { Triangle = 0, Point = 1, Directional = 2, Environment = 3, Spot = 4 };

// One entry of the light list that next-event estimation chooses from.
struct Light {
  LightType type = LightType::Point;
  uint32_t triangle = 0;  // Triangle lights: the emissive triangle
  Vec3 vector;            // Point, Spot: position; Directional: direction the light travels
  Rgb value;              // Point, Spot: intensity (W/sr; a spot's on its axis); Directional: irradiance
                          // normal to it; others unused
  // Spot: the axis it shines along, and KHR_lights_punctual's angular falloff, the square of
  // saturate(cos(angle to the axis) * angleScale + angleOffset) (spotFalloff).
  Vec3 axis{0, 0, -1};
  float angleScale = 0, angleOffset = 1;
};

// A light that only next-event estimation samples: no ray hits a point, spot or directional light.
inline bool isDeltaLight(const Light& light) {
  return light.type == LightType::Point || light.type == LightType::Directional || light.type == LightType::Spot;
}

// A spot light's share of its axial intensity in direction d (unit, away from the light).
inline float spotFalloff(const Light& light, Vec3 d) {
  const float a = std::clamp(dot(d, light.axis) * light.angleScale + light.angleOffset, 0.0f, 1.0f);
  return a * a;
}
// The falloff integrated over the sphere (steradians): 2 pi times the integral over c = cos(angle)
// of saturate(c s + o)^2, which is (s + o)^3 / (3 s) on the ramp (capped at 1) plus 1 - c where
// the falloff is 1.
inline float spotSolidAngle(const Light& light) {
  const float s = light.angleScale, o = light.angleOffset;
  const float top = std::min(1.0f, s + o), full = std::min(1.0f, (1.0f - o) / s);
  return 2.0f * kPi * (top * top * top / (3.0f * s) + (1.0f - full));
}

struct Camera {
  Vec3 eye{0, 0, 0}, lookAt{0, 0, -1}, up{0, 1, 0};
  float fovY = 45.0f;  // degrees
  int width = 512, height = 512;
};

// Constant radiance, or a latitude-longitude map (its radiance times `scale`), importance-sampled
// by texel luminance times sin(theta).
struct Environment {
  bool present = false;
  Rgb radiance{0.0f};  // constant environment
  uint32_t width = 0, height = 0;
  std::vector<Rgb> texels;  // lat-long map, empty for a constant environment
  Distribution2D distribution;
  std::string source;  // the map's path, for metadata
  // Texels of the map slightly below 0 that were clamped to 0, and the most negative value (the
  // loader's warning).
  uint32_t clampedTexels = 0;
  float mostNegativeTexel = 0;
};

// A scene file's "render" block: the method and options a batch job renders it with (the command
// line overrides them). The options are kept as text, by name, for the method's declaration to
// read (pipeline/method.h); the scene itself does not depend on them.
struct RenderBlock {
  bool present = false;
  std::string method;  // empty: none named
  std::vector<std::pair<std::string, std::string>> options;
};

// A vertex's tangent, for normal textures: the direction in which u grows, and the sign with which
// the bitangent cross(normal, direction) * sign points where v grows (Lucent's v, which runs up the
// image: glTF's TANGENT convention, MikkTSpace's).
struct Tangent {
  Vec3 direction;
  float sign = 1.0f;
};
static_assert(sizeof(Tangent) == 16);

// glTF's COLOR_0 at a vertex: it multiplies the base colour and the base alpha.
struct VertexColour {
  Rgb rgb{1.0f};
  float alpha = 1.0f;
};
static_assert(sizeof(VertexColour) == 16);

inline constexpr size_t kMostNearbyLights = 64;

struct Scene {
  // Vertices (one entry per unique position/normal/uv combination).
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;    // shading normals; zero where the OBJ had none (geometric is used)
  std::vector<Vec2> texcoords;   // zero where the OBJ had none
  std::vector<Vec2> texcoords1;  // glTF's TEXCOORD_1 where a texture reads it (else empty), zero where a mesh has none
  std::vector<Tangent> tangents;  // empty, or one per vertex (zero direction where none is known)
  std::vector<VertexColour> colours;  // glTF's COLOR_0 where a mesh has one (else empty), white where a mesh has none
  // Triangles.
  std::vector<uint32_t> indices;      // 3 per triangle
  std::vector<uint32_t> materialIds;  // 1 per triangle
  std::vector<Vec3> faceNormals;      // unit counter-clockwise normal per triangle (finalizeScene)
  std::vector<float> faceAreas;       // per triangle (finalizeScene)
  std::vector<Material> materials;
  std::vector<std::string> materialNames;
  std::vector<Texture> textures;
  std::vector<uint32_t> texels;
  // Lights: one per emissive triangle, then point and directional lights, then the environment.
  std::vector<Light> lights;
  Distribution1D lightDistribution;       // by each light's estimated power (lightChoiceOf)
  // Where a scene has from two to kMostNearbyLights point and spot lights, these (ascending): light
  // choice shares their cells of lightDistribution among them by power over squared distance from
  // the receiver (chooseLight, which weighs each of them per choice).
  std::vector<uint32_t> nearbyLights;
  std::vector<int32_t> triangleLight;     // light index of each triangle, -1 if not emissive
  Environment environment;
  Camera camera;
  Bounds3 bounds;
  uint64_t contentHash = 0;  // hash of geometry, materials, lights, camera: for image metadata
  uint32_t droppedDegenerateTriangles = 0;
  std::string sourcePath;
  std::vector<std::string> inputFiles;  // every file the scene was read from (JSON, OBJ, MTL, images)
  // What the scene's files hold that the render leaves out (a glTF material's specular lobe, an
  // extension not read), each with what it would change: reported with every render.
  std::vector<std::string> ignored;
  RenderBlock render;

  uint32_t triangleCount() const { return static_cast<uint32_t>(materialIds.size()); }
  Vec3 vertex(uint32_t tri, int k) const { return positions[indices[3 * tri + k]]; }
  float triangleArea(uint32_t tri) const { return faceAreas[tri]; }
  // The triangles' area in all (one side of each).
  double surfaceArea() const {
    double area = 0;
    for (float a : faceAreas) area += a;
    return area;
  }
  Vec3 geometricNormal(uint32_t tri) const { return faceNormals[tri]; }
  // Bounding sphere of the scene, used to place directional and environment emission.
  Vec3 boundingCenter() const { return bounds.center(); }
  float boundingRadius() const { return 0.5f * length(bounds.extent()); }
};

// Whether any material has holes (glTF alpha masks and blending): methods that place points on the
// surfaces refuse such scenes, whose points would cover the holes.
inline bool hasCutOutSurfaces(const Scene& scene) {
  for (const Material& m : scene.materials)
    if (m.alphaMode != AlphaMode::Opaque) return true;
  return false;
}

// Computes face normals and areas, the light list, the light distribution and the content hash
// once geometry and materials are set.
// Used by the loader and by tests that build scenes in code.
void finalizeScene(Scene& scene);

// A distribution over `lights` by `weights` (one each) in which every delta light of positive
// weight owns a grid cell (Distribution1D): however small its weight, it is chosen now and then, as
// it must be, next-event estimation being its only strategy.
Distribution1D lightChoiceOf(std::span<const Light> lights, std::span<const float> weights);

// A triangle's unit counter-clockwise normal and area from its corners, as faceNormals and
// faceAreas hold them: in float, and in double where the float cross product's squared length
// overflows (corners more than about 1e9 apart; coordinates go up to 1e15).
struct TriangleGeometry {
  Vec3 normal;
  float area = 0;
};
TriangleGeometry triangleGeometry(Vec3 p0, Vec3 p1, Vec3 p2);

// Hash of everything that determines an image: geometry, materials, textures, lights, environment
// and camera. Recompute it after changing the scene (e.g. the camera resolution).
uint64_t sceneContentHash(const Scene& scene);
// Scene::contentHash as Lucent writes it (lucent:scene_hash, film files, dump settings): lower-case hex.
std::string contentHashText(const Scene& scene);

}  // namespace lucent
