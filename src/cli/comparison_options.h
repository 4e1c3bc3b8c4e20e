// What lucent compare and lucent report share: the layer options, FLIP's observer and the choice
// between LDR-FLIP and HDR-FLIP.
#pragma once
#include <CLI/CLI.hpp>
#include <stdexcept>
#include <string>

#include "lucent/image/flip.h"

namespace lucent::cli {

// --layer NAME and --image-layer NAME; `candidate` names what is compared with the reference
// ("the image", "each candidate").
inline void addLayerOptions(CLI::App* cmd, std::string& layer, std::string& imageLayer, const std::string& candidate) {
  CLI::Option* layerOption = cmd->add_option(
      "--layer", layer,
      "Compare the reference's layer NAME (or paths.NAME: render --paths) with " + candidate +
          "'s layer of that name, or with the whole of it where it has none");
  cmd->add_option("--image-layer", imageLayer, "With --layer: " + candidate + "'s layer to compare, by its own name")
      ->needs(layerOption);
}

inline constexpr const char* kPixelsPerDegreeHelp =
    "FLIP's observer: pixels per degree of visual angle, in [1, 1000] (default 67.02: a 0.7 m wide 4K display seen "
    "from 0.7 m)";

// Checked here, not by CLI11, whose range checks let NaN through.
inline void checkPixelsPerDegree(double ppd) {
  if (!(ppd >= 1 && ppd <= 1000)) throw std::invalid_argument("--ppd must lie in [1, 1000]");
}

// LDR-FLIP between two 8-bit sRGB files (display images), HDR-FLIP otherwise.
inline FlipOptions flipOptions(bool candidateIsSrgb, bool referenceIsSrgb, double ppd) {
  FlipOptions options;
  options.pixelsPerDegree = ppd;
  options.hdr = !(candidateIsSrgb && referenceIsSrgb);
  return options;
}

}  // namespace lucent::cli
