#include "lucent/core/files.h"

#include <unistd.h>

#include <atomic>

namespace lucent {

namespace {

std::filesystem::path temporaryPathFor(const std::filesystem::path& path) {
  static std::atomic<unsigned> counter{0};
  std::string name = ".";
  name += path.stem().string() + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) +
          path.extension().string();
  return path.parent_path() / name;
}

}  // namespace

void writeFileAtomically(const std::filesystem::path& path, const std::string& what,
                         const std::function<void(const std::filesystem::path& tmp)>& write) {
  const std::filesystem::path tmp = temporaryPathFor(path);
  auto removeTmp = [&] {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
  };
  auto fail = [&](const std::string& why) {
    removeTmp();
    throw std::runtime_error("cannot write " + what + " '" + path.string() + "': " + why);
  };
  try {
    write(tmp);
  } catch (const WriteFailure& e) {
    fail(e.what());
  } catch (...) {
    removeTmp();
    throw;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail(ec.message());
}

}  // namespace lucent
