// What lucent compare and lucent report share: the layer options and FLIP's observer's help
// (lucent/image/comparison.h checks it and chooses between LDR-FLIP and HDR-FLIP).
#pragma once
#include <CLI/CLI.hpp>
#include <stdexcept>
#include <string>

#include "lucent/image/comparison.h"

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

}  // namespace lucent::cli
