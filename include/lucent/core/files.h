// Files written whole or not at all: to a temporary name beside the target, then renamed over it.
#pragma once
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace lucent {

// What a writer passed to writeFileAtomically throws when it cannot write: the reason.
struct WriteFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Calls write(tmp) to write a temporary file beside `path` (same directory, so that the rename is
// atomic; hidden, unique per process and call, keeping the extension, from which OpenImageIO picks
// the format), then renames it over `path`. On any failure the temporary file is removed; a
// WriteFailure or a failed rename becomes std::runtime_error("cannot write <what> '<path>': <why>").
void writeFileAtomically(const std::filesystem::path& path, const std::string& what,
                         const std::function<void(const std::filesystem::path& tmp)>& write);

// One file of a set written as one.
struct FileToWrite {
  std::filesystem::path path;
  std::string what;
  std::function<void(const std::filesystem::path& tmp)> write;
};
// Writes every file to its temporary name, then renames them all: if any fails to be written,
// none is renamed and every temporary file is removed (a failed PNG leaves no EXR behind).
void writeFilesAtomically(const std::vector<FileToWrite>& files);

// Why `path` cannot be read as a regular file ("not found", "is not a regular file" for a
// directory or device, or the system's reason such as a symbolic link loop), or "" if it can. Never
// throws.
std::string regularFileProblem(const std::filesystem::path& path);

// Removes the temporary files that writes into `directory` by processes no longer running (killed
// while writing) left behind. Writes call it for their target's directory.
void removeStaleTemporaryFiles(const std::filesystem::path& directory);

}  // namespace lucent
