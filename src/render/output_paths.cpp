#include "render/output_paths.h"

#include <filesystem>
#include <stdexcept>

#include "lucent/core/files.h"

namespace lucent {
namespace fs = std::filesystem;

void checkOutputFile(const std::string& path, const std::string& extension, const std::string& flag,
                     const std::vector<std::string>& inputs) {
  if (fs::path(path).extension() != extension)
    throw std::invalid_argument(flag + " '" + path + "' must end in " + extension);
  const fs::path dir = fs::absolute(path).parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw std::invalid_argument(flag + ": directory '" + dir.string() + "' does not exist");
  if (const std::string clash = inputFileClash(path, inputs); !clash.empty())
    throw std::invalid_argument(flag + " '" + path + "': " + clash + "; choose another output");
  try {
    checkWritable(path, flag);
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument(e.what());
  }
}

}  // namespace lucent
