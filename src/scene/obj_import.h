// OBJ/MTL import into the flat scene arrays (internal to the loader).
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "lucent/scene/scene.h"

namespace lucent::detail {

// A material as written in an MTL file (and then completed by the scene file), before it is
// classified into a Lucent material.
struct MaterialSpec {
  std::string name;
  Rgb kd{0.0f}, ks{0.0f}, ke{0.0f}, tf{0.0f};
  float ns = 1.0f, ni = 1.0f;
  int illum = 0;
  std::string mapKd;                 // absolute path, empty for none; for mapKdBytes, a name ending .png or .jpg
  std::vector<unsigned char> mapKdBytes;  // the texture's file held in memory (a glTF file's image), or none
  std::string mapKdOrigin;           // "file:line" (or the scene's key) that names it
  std::optional<MaterialType> type;  // set by the scene file's "type"
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
