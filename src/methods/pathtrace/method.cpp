// --method pt: the path tracer's options, declared once, and its entry in the method list.
#include "lucent/methods/pathtrace.h"
#include "lucent/pipeline/render_options.h"

namespace lucent {

namespace {
// The most samples a pixel takes with an error target where --spp is not given: the target, not a
// cap, ends the render.
constexpr int kTargetErrorSpp = 65536;
}  // namespace

const OptionTable<PathTraceOptions>& pathTraceOptionTable() {
  static const OptionTable<PathTraceOptions> table = [] {
    using O = PathTraceOptions;
    OptionTable<O> t;
    t.include(&O::common, commonOptionTable("samples per pixel (the most any pixel takes with a time budget or an error target)"));
    t.integer("max_depth", &O::maxDepth, 0, 1 << 24, "bounces",
              "path length: 1 is direct light alone, 2 adds one indirect bounce");
    t.integer("roulette_depth", &O::rouletteDepth, 1, 1 << 16, "bounces",
              "Russian roulette from this bounce on");
    t.choice("roulette", &O::roulette,
             std::vector<std::pair<std::string, RouletteKind>>{{"contribution", RouletteKind::Contribution},
                                                               {"throughput", RouletteKind::Throughput}},
             "contribution: paths go on by what they are expected to add to their pixel's relative error, from the "
             "first 8 samples per pixel on; throughput: by their throughput alone");
    t.choice("light_choice", &O::lightChoice,
             std::vector<std::pair<std::string, LightChoiceKind>>{{"learned", LightChoiceKind::Learned},
                                                                  {"power", LightChoiceKind::Power}},
             "learned: next-event estimation chooses among kinds of light (emitters, environment, point and "
             "directional lights) by what their samples brought in the first 8 samples per pixel (with "
             "--roulette contribution); power: by the lights' power");
    t.real("time_budget", &O::timeBudget, 0, 1e9, "s",
           "stop sampling within this many seconds (at least one sample per pixel); 0: no budget");
    t.real("target_error", &O::targetError, 0, 1, "relMSE",
           "render until the image's estimated relMSE against the converged image is at most this, spending samples "
           "where the pixels' errors are largest (with --spp the most a pixel takes, 65536 unless given; --time-budget "
           "a limit); 0: no target");
    t.defaultWhen("spp", [](const O& o) { return o.targetError > 0; }, std::to_string(kTargetErrorSpp));
    t.rule("target_error", [](const O& o) {
      // Each pixel's samples alternate between two streams, a pair per pass.
      return o.targetError > 0 && o.common.spp < 8 ? "needs at least 8 samples per pixel (--spp), its first pass" : "";
    });
    t.integer("tile_size", &O::tileSize, 1, 4096, "pixels",
              "side of the tiles the image is rendered in (does not change the image)");
    t.imageNeutral("tile_size");
    t.choice("strategy", &O::strategy,
             std::vector<std::pair<std::string, PathStrategy>>{
                 {"mis", PathStrategy::Mis}, {"light", PathStrategy::LightSampling}, {"bsdf", PathStrategy::BsdfSampling}},
             "mis combines light and BSDF sampling; light or bsdf alone, for validating the other two");
    t.choice("sampler", &O::sampler,
             std::vector<std::pair<std::string, SamplerKind>>{{"independent", SamplerKind::Independent},
                                                              {"sobol", SamplerKind::Sobol}},
             "random numbers: independent, or an Owen-scrambled Sobol sequence padded per bounce and purpose, each light "
             "point stratified with the direction its path arrived along");
    t.flag("variance", &O::variance,
           "add the variance of each pixel's mean (variance.R, .G, .B), for lucent compare --test");
    t.rule("variance", [](const O& o) {
      // The spread of a pixel's samples says how its mean varies only for independent samples:
      // the Sobol sampler's mean varies less.
      return !o.variance                                  ? ""
             : o.common.spp < 2                                  ? "needs at least 2 samples per pixel (--spp)"
             : o.sampler != SamplerKind::Independent      ? "needs --sampler independent (a Sobol pixel's samples are not independent)"
                                                          : "";
    });
    t.flag("paths", &O::paths,
           "add the light split by path as layers paths.NAME: emission, direct, indirect.1, .2, .3+ (third and "
           "later bounces), each also .diffuse and .glossy by the first non-specular vertex's reflection, and "
           "diffuse and glossy; with --variance each with its variance");
    t.flag("pixel_centres", &O::pixelCentres,
           "every camera ray through its pixel's centre (the reference for methods at one sample per pixel)");
    t.rule("pixel_centres", [](const O& o) {
      return o.pixelCentres && o.common.pixelFilter != PixelFilterKind::Box ? "samples no pixel filter: leave out --pixel-filter"
                                                                              : "";
    });
    return t;
  }();
  return table;
}

const Method& pathTraceMethod() {
  static const DeclaredMethod<PathTraceOptions> method(
      "pt", "the unbiased reference path tracer: next-event estimation and BSDF sampling by MIS",
      pathTraceOptionTable(), renderPathTraced, true, TransmissionRendered::All);
  return method;
}

}  // namespace lucent
