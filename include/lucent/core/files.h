// Files written whole or not at all: to a temporary name beside the target, then renamed over it.
#pragma once
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>

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

}  // namespace lucent
