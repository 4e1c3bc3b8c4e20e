// OBJ/MTL import into the flat scene arrays (internal to the loader).
#pragma once
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "lucent/scene/scene.h"

namespace lucent::detail {

// An image a material reads: a file, or a glTF file's image held in memory.
struct TextureFile {
  std::string path;                  // absolute path, empty for none; for `bytes`, a name ending .png or .jpg
  std::vector<unsigned char> bytes;  // the image's file held in memory (a glTF file's image), or none
  std::string origin;                // "file:line" (or the scene's key, or the glTF path) that names it
  TextureWrap wrapU = TextureWrap::Repeat, wrapV = TextureWrap::Repeat;  // a glTF sampler's
  bool nearest = false;
  uint32_t set = 0;                  // the texture coordinates it reads (Texture::set)
  bool transformed = false;          // Texture::transformed and transform (Lucent's coordinates)
  std::array<float, 6> transform = {1, 0, 0, 0, 1, 0};
  bool empty() const { return path.empty(); }
};

// A material as written in an MTL file or a glTF file (and then completed by the scene file),
// before it is classified into a Lucent material.
struct MaterialSpec {
  std::string name;
  Rgb kd{0.0f}, ks{0.0f}, ke{0.0f}, tf{0.0f};
  float ns = 1.0f, ni = 1.0f;
  int illum = 0;
  TextureFile mapKd;                 // map_Kd, or a glTF base colour texture (sRGB)
  std::optional<MaterialType> type;  // set by the scene file's "type" or by the glTF import
  float metallic = 0.0f, roughness = 1.0f, specular = 1.0f;  // glTF only
  GgxMasking masking = GgxMasking::Separable;                // glTF only
  TextureFile metallicRoughness;     // glTF only (linear)
  TextureFile normal;                // glTF only (linear)
  float normalScale = 1.0f;
  bool bendNormalMap = false;        // glTF only: Material::bendsNormalMap
  Rgb sheenColour{0.0f};             // glTF only: KHR_materials_sheen's factors and textures (sRGB; A linear)
  float sheenRoughness = 0.0f;
  TextureFile sheenColourTexture, sheenRoughnessTexture;
  float clearcoat = 0.0f, clearcoatRoughness = 0.0f;  // glTF only: KHR_materials_clearcoat's (textures linear)
  TextureFile clearcoatTexture, clearcoatRoughnessTexture, clearcoatNormalTexture;
  float clearcoatNormalScale = 1.0f;
  float transmission = 0.0f;         // glTF only: KHR_materials_transmission's (texture linear)
  TextureFile transmissionTexture;
  bool boundsVolume = false;         // glTF only: KHR_materials_volume's (thicknessFactor > 0)
  Rgb attenuationColour{1.0f};
  float attenuationDistance = kInf;
  TextureFile emissive;              // glTF only (sRGB), multiplies ke
  TextureFile specularTexture, specularColourTexture;  // glTF only: KHR_materials_specular's (A linear; sRGB)
  bool doubleSided = false;          // an emitter's back faces emit too (glTF's doubleSided, a scene file's double_sided)
  bool singleSided = false;          // glTF's doubleSided false: camera rays do not see the back faces (Material::culledBehind)
  AlphaMode alphaMode = AlphaMode::Opaque;  // glTF only
  float alphaCutoff = 0.5f, baseAlpha = 1.0f;
  std::string origin;                // "file:line" of its definition, for error messages
};

struct ObjImport {
  std::map<std::string, uint32_t> materialIndex;  // name -> index into specs
  std::vector<MaterialSpec> specs;
  std::vector<std::string> libraries;             // the MTL files read
};

// Validates the OBJ (and its MTL files) line by line, then appends its triangles to `scene`, with
// material ids indexing `import.specs`. Throws SceneError naming the file and line.
void importObj(const std::string& objPath, Scene& scene, ObjImport& import);

// Turns a completed spec into a Lucent material, checking it is physically valid.
Material classifyMaterial(const MaterialSpec& spec);

}  // namespace lucent::detail
