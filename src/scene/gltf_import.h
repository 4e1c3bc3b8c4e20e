// glTF 2.0 import (.gltf with external or embedded buffers, .glb) into the flat scene arrays,
// internal to the loader. Read by Debian's TinyGLTF; every index, count and byte range is checked
// here before it is used, and every problem names the file and the JSON path of what is wrong.
#pragma once
#include <optional>
#include <string>

#include "lucent/scene/loader.h"
#include "lucent/scene/scene.h"
#include "obj_import.h"

namespace lucent::detail {

// What a glTF file gives besides its triangles and materials.
struct GltfContent {
  std::optional<Camera> camera;  // the first camera in the scene's nodes, its resolution from its aspect
};

// Appends the triangles of the file's scene (its default scene, else its first), every node's mesh
// placed by the node's world transform (a mesh used by several nodes is placed once for each),
// with their materials as specs in `import`, and the scene's KHR_lights_punctual lights. What the
// render leaves out of the file is listed in scene.ignored. Throws SceneError.
void importGltf(const std::string& path, const GltfOptions& options, Scene& scene, ObjImport& import,
                GltfContent& content);

}  // namespace lucent::detail
