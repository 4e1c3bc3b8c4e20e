// The settings file beside a render's stage dumps (docs/dump-format.md, "Settings"); apart from
// dumps.h so that the methods' interface (method.h) names no film or shading-point type.
#pragma once
#include <string>

#include "lucent/core/stats.h"
#include "lucent/scene/scene.h"

namespace lucent {

// <directory>/settings.json (docs/dump-format.md, "Settings"): what a backend needs beside the
// arrays to run a stage's kernel: the method, every option's value (`optionsJson`, as
// optionsJsonText gives them), the values the method derived from them and the scene (the search
// radius, the point count, ...), and the image's size, camera and scene. Written whole or not at
// all, after the render; throws std::runtime_error naming the file when it cannot.
void writeDumpSettings(const std::string& directory, const std::string& method, const std::string& optionsJson,
                       const RenderStats& stats, const Scene& scene);

}  // namespace lucent
