// Loading a scene from its JSON file and OBJ/MTL or glTF files, or from a glTF file alone
// (docs/scene-format.md).
#pragma once
#include <stdexcept>
#include <string>

#include "lucent/scene/scene.h"

namespace lucent {

// Every problem with the input: the message names the file and the line or JSON key.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// How glTF files are read where the file leaves a choice to the renderer.
struct GltfOptions {
  // Smith's masking-shadowing term: the height-correlated form of Appendix B (since the
  // specification's revision of January 2026) and of most GPU engines, or the separable product
  // the appendix gave before (to compare a backend with the model it implements).
  bool heightCorrelated = true;
  // Normal-mapped shading normals bent, per viewing direction, just enough that the mirror
  // direction stays above the surface (bentForReflection, surface.h), as production renderers do;
  // false: as the texture gives them, where reflections below the surface are lost (dark rims).
  bool bendNormalMaps = true;
  // KHR_lights_punctual's photometric intensities (candela, lux) to Lucent's radiometric ones:
  // lumens per watt (683, the luminous efficacy of 555 nm light, as Blender's importer uses).
  double lumensPerWatt = 683.0;
  // The camera a glTF file is rendered from on its own: its node's name or its own; empty: the
  // first in the scene's node order.
  std::string camera;
};

struct LoadOptions {
  bool quiet = false;  // suppress warnings (e.g. dropped degenerate triangles) on stderr
  GltfOptions gltf;    // for every glTF file, unless a scene file's entry sets its own
  LoadOptions(bool quiet = false, GltfOptions gltf = {}) : quiet(quiet), gltf(gltf) {}
};

// A .gltf or .glb path loads that file with its first camera (512 pixels wide, as high as its aspect
// ratio makes it); any other path is a scene file.
Scene loadScene(const std::string& path, const LoadOptions& options = {});

}  // namespace lucent
