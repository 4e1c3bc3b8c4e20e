// What another backend's program does with an installed Lucent: load a scene, render it with a
// method's typed options (and with any method by name), compare images, read a stage dump.
// Renders the Cornell box with the path tracer at 16 x 16 (16 samples per pixel, seed 1) and
// requires it identical to REFERENCE.exr (rendered the same way by `lucent render`), by the typed
// call, by name and through a RenderSession, whose EXR must hold the same pixels; then renders it
// with purcell, dumping its stages into DUMPS, and reads the
// photons back. Every supported header is included: each compiles from the installed tree alone.
//   consumer SCENE.json REFERENCE.exr DUMPS (RenderSession's image: DUMPS/../rendered.exr)
#include <cstdio>
#include <exception>
#include <string>

#include "lucent/core/dump.h"
#include "lucent/image/image.h"
#include "lucent/image/metrics.h"
#include "lucent/methods/envpbgi.h"
#include "lucent/methods/methods.h"
#include "lucent/methods/microrender.h"
#include "lucent/methods/particles.h"
#include "lucent/methods/pathtrace.h"
#include "lucent/methods/photonmap.h"
#include "lucent/scene/loader.h"
#include "lucent/render/render_session.h"
#include "lucent/techniques/photons/photon.h"
#include "lucent/techniques/points/point_nodes.h"
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
    const lucent::Image reference = lucent::readImage(argv[2]);

    lucent::PathTraceOptions pt;
    pt.common.spp = 16;
    pt.common.seed = 1;
    const lucent::ImageError typed = lucent::compareImages(lucent::renderPathTraced(scene, visibility, pt).image, reference);
    const lucent::ImageError byName = lucent::compareImages(
        lucent::renderingMethod("pt").render(scene, visibility, {{"spp", "16"}, {"seed", "1"}}).image, reference);
    std::printf("consumer: pt, RMSE %g (typed options) and %g (by name) against the reference\n", typed.overall.rmse,
                byName.overall.rmse);
    if (typed.overall.rmse != 0 || typed.nonFinite != 0 || byName.overall.rmse != 0 || byName.nonFinite != 0) return 1;

    lucent::SceneSettings settings;
    settings.load.quiet = true;
    settings.resolution = {16, 16};
    lucent::OpenScene opened(argv[1], settings);
    const std::string written = std::string(argv[3]) + "/../rendered.exr";
    const lucent::RenderResult rendered =
        lucent::RenderSession(opened, {.method = "pt", .options = {{"spp", "16"}, {"seed", "1"}}, .output = written}).run();
    const lucent::ImageError bySession = lucent::compareImages(lucent::readImage(written), reference);
    std::printf("consumer: pt, RMSE %g through a RenderSession (%s)\n", bySession.overall.rmse, rendered.summary.c_str());
    if (bySession.overall.rmse != 0 || bySession.nonFinite != 0) return 1;

    lucent::PhotonMapOptions purcellOptions;
    purcellOptions.photons = 2000;
    purcellOptions.causticPhotons = 0;
    purcellOptions.shading.dumpDirectory = argv[3];
    const lucent::RenderOutput purcell = lucent::renderPurcell(scene, visibility, purcellOptions);
    const auto photons = lucent::readDump<lucent::Photon>(std::string(argv[3]) + "/global.photons.bin", "Photon");
    std::printf("consumer: purcell, %zu photons dumped, %llu in the map\n", photons.size(),
                static_cast<unsigned long long>(purcell.stats.counter("global_photons")));
    return !photons.empty() && photons.size() == purcell.stats.counter("global_photons") ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 2;
  }
}
