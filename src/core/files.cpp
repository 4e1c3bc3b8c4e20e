#include "lucent/core/files.h"

#include <unistd.h>

#include <atomic>
#include <string>

namespace lucent {

std::filesystem::path temporaryPathFor(const std::filesystem::path& path) {
  static std::atomic<unsigned> counter{0};
  std::string name = ".";
  name += path.stem().string() + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) +
          path.extension().string();
  return path.parent_path() / name;
}

}  // namespace lucent
