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

struct LoadOptions {
  bool quiet = false;  // suppress warnings (e.g. dropped degenerate triangles) on stderr
};

// A .gltf or .glb path loads that file with its first camera (512 pixels wide, as high as its aspect
// ratio makes it); any other path is a scene file.
Scene loadScene(const std::string& path, const LoadOptions& options = {});

}  // namespace lucent
