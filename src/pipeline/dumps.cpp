#include "lucent/pipeline/dumps.h"

#include "lucent/core/dump.h"

namespace lucent {

void dumpShadingPoints(const std::string& dir, const std::string& prefix, const EyePaths& eye,
                       const PointRadiance& light, bool caustic) {
  writeDump(dir, prefix + "shading_points", "ShadingPoint", std::span(eye.points));
  writeDump(dir, prefix + "direct", "Rgb", std::span(light.direct));
  writeDump(dir, prefix + "indirect", "Rgb", std::span(light.indirect));
  if (caustic) writeDump(dir, prefix + "caustic", "Rgb", std::span(light.caustic));
}

}  // namespace lucent
