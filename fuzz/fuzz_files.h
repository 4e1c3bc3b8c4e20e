// What the fuzz targets share: a scratch directory of the process's own, and writing an input's
// bytes into it.
#pragma once
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace lucent::fuzz {

// A directory of this process's own, in memory where /dev/shm exists, removed at exit.
inline const std::filesystem::path& scratchDirectory() {
  static const std::filesystem::path dir = [] {
    std::string pattern = (std::filesystem::is_directory("/dev/shm") ? std::string("/dev/shm")
                                                                     : std::filesystem::temp_directory_path().string()) +
                          "/lucent-fuzz-XXXXXX";
    if (!mkdtemp(pattern.data())) std::abort();
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(scratchDirectory(), ec);
    });
    return std::filesystem::path(pattern);
  }();
  return dir;
}

inline void writeFile(const std::filesystem::path& path, std::string_view content) {
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(content.data(), std::streamsize(content.size()));
}

}  // namespace lucent::fuzz
