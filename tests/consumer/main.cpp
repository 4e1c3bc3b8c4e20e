// What another backend's program does with an installed Lucent: load a scene, render it with any
// method by name, compare images, read a stage dump. Renders the Cornell box with the path tracer
// at 16 x 16 (16 samples per pixel, seed 1) and requires it identical to REFERENCE.exr (rendered
// the same way by `lucent render`); then renders it with purcell, dumping its stages into DUMPS,
// and reads the photons back.   consumer SCENE.json REFERENCE.exr DUMPS
#include <cstdio>
#include <exception>

#include "lucent/core/dump.h"
#include "lucent/image/image.h"
#include "lucent/image/metrics.h"
#include "lucent/methods/methods.h"
#include "lucent/scene/loader.h"
#include "lucent/techniques/photons/photon.h"
#include "lucent/trace/visibility.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: consumer SCENE.json REFERENCE.exr DUMPS\n");
    return 2;
  }
  try {
    lucent::Scene scene = lucent::loadScene(argv[1], {true});
    scene.camera.width = scene.camera.height = 16;
    const lucent::Visibility visibility(scene);
    const lucent::Image image =
        lucent::renderingMethod("pt").render(scene, visibility, {{"spp", "16"}, {"seed", "1"}}).image;
    const lucent::ImageError error = lucent::compareImages(image, lucent::readImage(argv[2]));
    std::printf("consumer: pt, RMSE %g against the reference\n", error.overall.rmse);
    if (error.overall.rmse != 0 || error.nonFinite != 0) return 1;

    const lucent::RenderOutput purcell = lucent::renderingMethod("purcell").render(
        scene, visibility, {{"photons", "2000"}, {"caustic_photons", "0"}, {"dump", argv[3]}});
    const auto photons = lucent::readDump<lucent::Photon>(std::string(argv[3]) + "/global.photons.bin", "Photon");
    std::printf("consumer: purcell, %zu photons dumped, %llu in the map\n", photons.size(),
                static_cast<unsigned long long>(purcell.stats.counter("global_photons")));
    return !photons.empty() && photons.size() == purcell.stats.counter("global_photons") ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 2;
  }
}
