// Loading a scene from its JSON file and OBJ/MTL files (docs/scene-format.md).
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

Scene loadScene(const std::string& jsonPath, const LoadOptions& options = {});

}  // namespace lucent
