// Files written whole or not at all: to a temporary name beside the target, then renamed over it.
#pragma once
#include <filesystem>

namespace lucent {

// Same directory (so that the rename is atomic), hidden, unique per process and call, and keeping
// the extension (OpenImageIO picks the file format from it).
std::filesystem::path temporaryPathFor(const std::filesystem::path& path);

}  // namespace lucent
