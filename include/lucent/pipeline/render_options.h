// The options that methods share, as structs that a method's options hold as members, and their
// declarations, made once here: a method's table includes them (OptionTable::include).
#pragma once
#include <cstdint>
#include <string>

#include "lucent/core/dump.h"
#include "lucent/core/pixel_filter.h"
#include "lucent/pipeline/options.h"

namespace lucent {

// Camera samples per band for methods that shade a band's points at once: the band's shading points
// (112 bytes each) stay below glibc's mmap threshold (32 MiB, as retainFreedMemory sets it), so that
// each band's arrays reuse the heap pages of the band before instead of touching fresh ones (slow on
// virtual machines).
inline constexpr uint64_t kReusableBandSamples = uint64_t(1) << 17;

// Every method's: samples per pixel, the seed and the layers.
struct CommonOptions {
  int spp = 1;
  PixelFilterKind pixelFilter = PixelFilterKind::Box;
  double filterRadius = 0;  // 0: the filter's own
  uint64_t seed = 0;
  bool layers = false;  // add the first hit's features, the light's parts and each pixel's surface as layers
};

// `sppHelp` says what a sample is to the method.
inline OptionTable<CommonOptions> commonOptionTable(std::string sppHelp) {
  using O = CommonOptions;
  OptionTable<O> t;
  t.integer("spp", &O::spp, 1, 1 << 24, "samples", std::move(sppHelp));
  t.choice("pixel_filter", &O::pixelFilter,
           {{"box", PixelFilterKind::Box},
            {"tent", PixelFilterKind::Tent},
            {"gaussian", PixelFilterKind::Gaussian},
            {"blackman-harris", PixelFilterKind::BlackmanHarris},
            {"mitchell", PixelFilterKind::Mitchell}},
           "the pixel filter, sampled by filter importance so that pixels stay independent: box (radius 0.5), tent "
           "(radius 1, as three.js-family GPU path tracers), gaussian (radius 1.5, sigma 0.5, as pbrt-v4), "
           "blackman-harris (width 1.5, as Cycles), mitchell (radius 2, B = C = 1/3, as pbrt-v4)");
  t.real("filter_radius", &O::filterRadius, 0, 16, "pixels", "the pixel filter's radius (0: the filter's own)");
  t.integer("seed", &O::seed, 0, 0x1p62, "", "random seed (the same seed gives the same image, whatever the threads)");
  t.flag("layers", &O::layers,
         "add the first hit's albedo, normal and depth, the light's parts and what each pixel's centre shows "
         "(surface.material, surface.emitter) as layers of the EXR");
  return t;
}
inline const char* const kCameraRaysHelp = "camera rays per pixel: one through the pixel's centre, more stratified over it";

template <class Options>
void declareMaxSpecularDepth(OptionTable<Options>& table, int Options::*field) {
  table.integer("max_specular_depth", field, 0, 64, "bounces", "mirror and glass bounces followed from the camera");
}

template <class Options>
void declareDumpDirectory(OptionTable<Options>& table, std::string Options::*field) {
  table.text("dump", field, "directory", "write every stage's arrays into this directory, created where missing (docs/dump-format.md)");
  table.imageNeutral("dump");
  table.rule("dump", [field](const Options& o) { return dumpDirectoryProblem(o.*field); });
}

// The methods' that follow camera paths through mirrors and glass to shading points and light them
// by shadow rays (pipeline/shading_points.h, direct_light.h), dumping their stages.
struct ShadingPointOptions {
  int maxSpecularDepth = 10;  // mirror and glass bounces followed from the camera
  int lightSamples = 32;      // shadow rays per shading point to area lights and the environment
  // Where each stage's arrays are dumped for checking another backend stage by stage
  // (docs/dump-format.md); empty: none.
  std::string dumpDirectory;
};

inline const OptionTable<ShadingPointOptions>& shadingPointOptionTable() {
  static const OptionTable<ShadingPointOptions> table = [] {
    using O = ShadingPointOptions;
    OptionTable<O> t;
    declareMaxSpecularDepth(t, &O::maxSpecularDepth);
    t.integer("light_samples", &O::lightSamples, 0, 1 << 16, "rays",
              "shadow rays per shading point to the area lights and the environment, besides one to each "
              "point or directional light (0: no direct light)");
    declareDumpDirectory(t, &O::dumpDirectory);
    return t;
  }();
  return table;
}

}  // namespace lucent
