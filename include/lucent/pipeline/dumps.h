// The pipeline's stage dumps (docs/dump-format.md): shading points and the light each part of the
// image gives them, so that another backend can be checked stage by stage.
#pragma once
#include <string>

#include "lucent/pipeline/film.h"
#include "lucent/pipeline/shading_points.h"

namespace lucent {

// <prefix>shading_points, <prefix>direct, <prefix>indirect and, where the method has a caustic
// part, <prefix>caustic, into `directory`.
void dumpShadingPoints(const std::string& directory, const std::string& prefix, const EyePaths& eye,
                       const PointRadiance& light, bool caustic);

}  // namespace lucent
