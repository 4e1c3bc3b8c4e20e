#include "lucent/pipeline/render_stages.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "lucent/core/stop.h"

namespace lucent {

RenderPart resolvePart(const RenderControl& control, const Scene& scene, int spp) {
  const PixelRect image{0, 0, scene.camera.width, scene.camera.height};
  RenderPart part;
  part.region = control.crop.empty() ? image : control.crop;
  if (!image.contains(part.region))
    throw std::invalid_argument("--crop " + std::to_string(part.region.x0) + "," + std::to_string(part.region.y0) + "," +
                                std::to_string(part.region.x1) + "," + std::to_string(part.region.y1) +
                                ": not inside the " + std::to_string(image.x1) + " x " + std::to_string(image.y1) +
                                " image");
  part.sampleBegin = control.firstSample;
  part.sampleEnd = control.sampleCount > 0 ? control.firstSample + control.sampleCount : spp;
  if (part.sampleBegin < 0 || part.sampleBegin >= part.sampleEnd || part.sampleEnd > spp)
    throw std::invalid_argument("--samples " + std::to_string(control.firstSample) + ":" +
                                std::to_string(control.sampleCount) + ": not inside the " + std::to_string(spp) +
                                " samples per pixel (--spp)");
  return part;
}

void refuseResume(const RenderControl& control, std::string_view atOnce) {
  if (control.resume || control.checkpointSeconds > 0)
    throw std::invalid_argument(std::string(atOnce) + " and cannot checkpoint or resume; render it in parts (--crop, "
                                "--samples) to bound the work a kill loses");
}

void addBand(Film& film, const EyePaths& band, const PointRadiance& light, int imageWidth, const RenderPart& part) {
  film.add(band, light);
  for (size_t i = 0; i < band.pixels.size(); ++i) film.setTaken(band.imagePixel(i, imageWidth), uint32_t(part.samples()));
}

EyePathSettings eyePathSettings(const CommonOptions& common, int maxSpecularDepth, const RenderPart& part) {
  EyePathSettings s;
  s.spp = common.spp;
  s.filter = {common.pixelFilter, common.filterRadius};
  s.maxSpecularDepth = maxSpecularDepth;
  s.seed = common.seed;
  s.layers = common.layers;
  s.region = part.region;
  s.sampleBegin = part.sampleBegin;
  s.sampleEnd = part.sampleEnd;
  return s;
}

}  // namespace lucent
