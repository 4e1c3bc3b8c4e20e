#include "lucent/core/files.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <regex>

namespace lucent {

namespace {

// ".<stem>.tmp-<pid>-<n><extension>", beside the target.
std::filesystem::path temporaryPathFor(const std::filesystem::path& path) {
  static std::atomic<unsigned> counter{0};
  std::string name = ".";
  name += path.stem().string() + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) +
          path.extension().string();
  return path.parent_path() / name;
}

void removeQuietly(const std::filesystem::path& path) {
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
}

}  // namespace

void removeStaleTemporaryFiles(const std::filesystem::path& directory) {
  static const std::regex temporary(R"(\..*\.tmp-([0-9]+)-[0-9]+(\.[A-Za-z0-9]+)?)");
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(directory.empty() ? "." : directory, ec)) {
    std::smatch m;
    const std::string name = entry.path().filename().string();
    if (!std::regex_match(name, m, temporary)) continue;
    const long pid = std::stol(m[1].str());
    // Gone: no such process (a process of another user answers EPERM, and is left alone).
    if (pid != ::getpid() && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH) removeQuietly(entry.path());
  }
}

void writeFilesAtomically(const std::vector<FileToWrite>& files) {
  // What would stop a rename, checked before anything is written or renamed.
  for (const FileToWrite& f : files) {
    std::error_code ec;
    if (std::filesystem::is_directory(f.path, ec))
      throw std::runtime_error("cannot write " + f.what + " '" + f.path.string() + "': it is a directory");
  }
  std::vector<std::filesystem::path> temporary;
  auto removeAll = [&] {
    for (const auto& tmp : temporary) removeQuietly(tmp);
  };
  for (const FileToWrite& f : files) {
    removeStaleTemporaryFiles(f.path.parent_path());
    temporary.push_back(temporaryPathFor(f.path));
    try {
      f.write(temporary.back());
    } catch (const WriteFailure& e) {
      removeAll();
      throw std::runtime_error("cannot write " + f.what + " '" + f.path.string() + "': " + e.what());
    } catch (...) {
      removeAll();
      throw;
    }
  }
  for (size_t i = 0; i < files.size(); ++i) {
    std::error_code ec;
    std::filesystem::rename(temporary[i], files[i].path, ec);
    if (ec) {
      for (size_t j = i; j < files.size(); ++j) removeQuietly(temporary[j]);
      throw std::runtime_error("cannot write " + files[i].what + " '" + files[i].path.string() + "': " + ec.message());
    }
  }
}

void writeFileAtomically(const std::filesystem::path& path, const std::string& what,
                         const std::function<void(const std::filesystem::path& tmp)>& write) {
  writeFilesAtomically({{path, what, write}});
}

std::string regularFileProblem(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) return "not found";
  if (ec) return "cannot be read: " + ec.message();
  if (status.type() != std::filesystem::file_type::regular) return "is not a regular file";
  return "";
}

}  // namespace lucent
