// The pipeline's stage dumps (docs/dump-format.md): shading points and the light each part of the
// image gives them, so that another backend can be checked stage by stage.
#pragma once
#include <string>

#include "lucent/core/stats.h"
#include "lucent/pipeline/film.h"
#include "lucent/pipeline/shading_points.h"
#include "lucent/scene/scene.h"

namespace lucent {

// <prefix>shading_points, <prefix>direct, <prefix>indirect and, where the method has a caustic
// part, <prefix>caustic, into `directory`.
void dumpShadingPoints(const std::string& directory, const std::string& prefix, const EyePaths& eye,
                       const PointRadiance& light, bool caustic);

// <directory>/settings.json (docs/dump-format.md, "Settings"): what a backend needs beside the
// arrays to run a stage's kernel: the method, every option's value (`optionsJson`, as
// optionsJsonText gives them), the values the method derived from them and the scene (the search
// radius, the point count, ...), and the image's size, camera and scene. Written whole or not at
// all, after the render; throws std::runtime_error naming the file when it cannot.
void writeDumpSettings(const std::string& directory, const std::string& method, const std::string& optionsJson,
                       const RenderStats& stats, const Scene& scene);

}  // namespace lucent
