// Loads a scene, renders it with the path tracer at 16 x 16 (16 samples per pixel, seed 1), and
// compares the image with a reference rendered the same way by `lucent render`: exit 0 when they
// are identical.   consumer SCENE.json REFERENCE.exr
#include <cstdio>
#include <exception>

#include "lucent/image/image.h"
#include "lucent/image/metrics.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/scene/loader.h"
#include "lucent/trace/visibility.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: consumer SCENE.json REFERENCE.exr\n");
    return 2;
  }
  try {
    lucent::Scene scene = lucent::loadScene(argv[1], {true});
    scene.camera.width = scene.camera.height = 16;
    const lucent::Visibility visibility(scene);
    lucent::PathTraceOptions options;
    options.spp = 16;
    options.seed = 1;
    const lucent::Image image = lucent::renderPathTraced(scene, visibility, options).image;
    const lucent::ImageError error = lucent::compareImages(image, lucent::readImage(argv[2]));
    std::printf("consumer: RMSE %g against the reference\n", error.overall.rmse);
    return error.overall.rmse == 0 && error.nonFinite == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 2;
  }
}
