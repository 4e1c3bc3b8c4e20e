// The options that methods share, each declared once here for every method that has it. A method's
// options struct names them alike (seed, layers, dumpDirectory; spp, lightSamples and
// maxSpecularDepth for the methods that shade camera paths' surface points), and its table calls
// these instead of declaring them again.
#pragma once
#include <string>

#include "lucent/core/dump.h"
#include "lucent/pipeline/options.h"

namespace lucent {

template <class Options>
void declareSeed(OptionTable<Options>& table) {
  table.integer("seed", [](Options& o) -> auto& { return o.seed; }, 0, 0x1p62, "",
                "random seed (the same seed gives the same image, whatever the threads)");
}

template <class Options>
void declareLayers(OptionTable<Options>& table) {
  table.flag("layers", [](Options& o) -> auto& { return o.layers; },
             "add the first hit's albedo, normal and depth and the light's parts as layers of the EXR");
}

template <class Options>
void declareDumpDirectory(OptionTable<Options>& table) {
  table.text("dump", [](Options& o) -> auto& { return o.dumpDirectory; }, "directory",
             "write every stage's arrays into this existing directory (docs/dump-format.md)");
  table.imageNeutral("dump");
  table.rule("dump", [](const Options& o) { return dumpDirectoryProblem(o.dumpDirectory); });
}

// Camera paths through mirrors and glass to shading points (pipeline/shading_points.h).
template <class Options>
void declareCameraPathOptions(OptionTable<Options>& table) {
  table.integer("spp", [](Options& o) -> auto& { return o.spp; }, 1, 1 << 24, "samples",
                "camera rays per pixel: one through the pixel's centre, more stratified over it");
  table.integer("max_specular_depth", [](Options& o) -> auto& { return o.maxSpecularDepth; }, 0, 64, "bounces",
                "mirror and glass bounces followed from the camera");
}

// Camera paths, and direct light at their shading points by shadow rays (pipeline/direct_light.h).
template <class Options>
void declareShadingPointOptions(OptionTable<Options>& table) {
  declareCameraPathOptions(table);
  table.integer("light_samples", [](Options& o) -> auto& { return o.lightSamples; }, 0, 1 << 16, "rays",
                "shadow rays per shading point to the area lights and the environment, besides one to each "
                "point or directional light (0: no direct light)");
}

}  // namespace lucent
