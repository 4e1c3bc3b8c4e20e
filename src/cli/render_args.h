// lucent render's arguments: its own flags, declared as the methods' options are
// (pipeline/options.h), and the chosen method's options, with the scene file's render block.
#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lucent/pipeline/method.h"
#include "lucent/pipeline/options.h"
#include "lucent/pipeline/pixel_rect.h"
#include "lucent/pipeline/render_control.h"
#include "lucent/scene/loader.h"
#include "lucent/scene/scene.h"

namespace lucent::cli {

struct RenderArgs {
  std::string scene, method, output, png, isa, part;
  std::pair<int, int> resolution{0, 0};  // width, height; 0: the camera's
  PixelRect crop;                        // empty: the whole image
  std::pair<int, int> samples{0, 0};     // first, count; count 0: all
  int threads = 0;
  double checkpointSeconds = 0;
  bool resume = false;
  uint64_t memoryLimit = 0;  // 0: the available memory
  bool quiet = false, robust = false, help = false, logStages = false, strict = false;
  bool gltfHeightCorrelated = true;
  bool gltfBendNormalMaps = true;
  double lumensPerWatt = GltfOptions{}.lumensPerWatt;
  std::string gltfCamera;
  OptionValues methodOptions;  // as given, in order
};

// The render command's own options, beside the method's: the help and the parsing read this table.
const OptionTable<RenderArgs>& renderFlags();

// Splits the arguments into the render command's own and the methods' (every method's options are
// known by name, so each can be told to take a value or not before the method is chosen); throws
// std::invalid_argument naming the flag.
RenderArgs parseRenderArgs(const std::vector<std::string>& args);

}  // namespace lucent::cli
