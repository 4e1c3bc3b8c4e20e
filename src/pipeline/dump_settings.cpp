#include "lucent/pipeline/dump_settings.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/json_text.h"
#include "lucent/core/dump.h"
#include "lucent/core/files.h"

namespace lucent {

void writeDumpSettings(const std::string& directory, const std::string& method, const std::string& optionsJson,
                       const RenderStats& stats, const Scene& scene) {
  auto vector = [](Vec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); };
  nlohmann::ordered_json settings;
  settings["method"] = method;
  settings["options"] = nlohmann::ordered_json::parse(optionsJson);
  settings["derived"] = nlohmann::ordered_json::object();
  for (const auto& [name, value] : stats.derived) settings["derived"][name] = value;
  settings["width"] = scene.camera.width;
  settings["height"] = scene.camera.height;
  settings["camera"] = {{"eye", vector(scene.camera.eye)}, {"look_at", vector(scene.camera.lookAt)},
                        {"up", vector(scene.camera.up)}, {"fov_y", scene.camera.fovY}};
  settings["scene"] = scene.sourcePath;
  settings["scene_hash"] = contentHashText(scene);
  settings["bounds"] = {{"min", vector(scene.bounds.lo)}, {"max", vector(scene.bounds.hi)}};
  settings["version"] = LUCENT_VERSION;
  const std::string text = jsonText(settings, 2) + "\n";
  createDumpDirectory(directory);
  writeFileAtomically(std::filesystem::path(directory) / "settings.json", "dump settings",
                      [&text](const std::filesystem::path& tmp) {
                        std::ofstream out(tmp, std::ios::binary);
                        out << text;
                        if (!out.flush()) throw WriteFailure("write failed (disk full?)");
                      });
}

}  // namespace lucent
