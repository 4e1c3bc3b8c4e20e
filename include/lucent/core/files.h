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
// atomic; hidden, unique per process and call, keeping the extension), then renames it over
// `path`. On any failure the temporary file is removed; a WriteFailure or a failed rename becomes
// std::runtime_error("cannot write <what> '<path>': <why>").
void writeFileAtomically(const std::filesystem::path& path, const std::string& what,
                         const std::function<void(const std::filesystem::path& tmp)>& write);

// One file of a set written as one.
struct FileToWrite {
  std::filesystem::path path;
  std::string what;
  std::function<void(const std::filesystem::path& tmp)> write;
};
// Writes every file to its temporary name, then renames them all: if any fails to be written,
// none is renamed and every temporary file is removed (a failed PNG leaves no EXR behind). A path
// that is one of the process's inputs (inputFileClash) is refused before anything is written.
// SIGINT, SIGTERM and SIGHUP that come while files are written act once they are renamed or removed,
// as they would have acted then: a signal never leaves a temporary file or a part of a set.
void writeFilesAtomically(const std::vector<FileToWrite>& files);

// Why `path` cannot be read as a regular file ("not found", "is not a regular file" for a
// directory, FIFO or device, which would read as empty, block or read for ever, or the system's
// reason such as a symbolic link loop), or "" if it can. Never throws.
std::string regularFileProblem(const std::filesystem::path& path);

// What every reader of a scene's files (JSON, OBJ, MTL, textures, environment maps, glTF files and
// their buffers and images) asks before it opens one: regularFileProblem(path), and when that is "",
// `path` becomes one of this process's inputs for the rest of its life (read again under the same
// name after the file was replaced, the file the name now leads to takes its place). No write of Lucent's replaces
// an input, whatever name reaches it: inputs are known by identity (device and inode), both of the
// name given and of the file it leads to, so a link, another spelling or a URI that a loader decoded
// cannot reach one. (Images to compare, films and dumps are named as inputs by the commands that
// read them: a process may rewrite its own films and dumps.)
std::string admitInputFile(const std::filesystem::path& path);

// Why `path` must not be written: "it is 'INPUT', a file this process reads" when it is one of the
// process's inputs (admitInputFile) or one of `alsoInputs` by identity; else "". Never throws.
std::string inputFileClash(const std::filesystem::path& path, const std::vector<std::string>& alsoInputs = {});

// The temporary name a write of `path` uses: ".<stem>.lucent-tmp.<boot>.<pid namespace>.<pid>.<start
// time>.<n><extension>", beside `path`, naming the process that writes it (the kernel's boot id,
// the process-id namespace, the process id and its start time in clock ticks after boot).
std::filesystem::path temporaryPathFor(const std::filesystem::path& path);

// Whether `name` is a temporary name of Lucent's whose writer is proven gone: written on this boot of
// this machine, in this process-id namespace, by a process that no longer runs (no process has its
// id, or the one that has it started at another time). Anything else, another program's file or one
// written on another machine included, is not.
bool isAbandonedTemporaryFile(const std::string& name);

// Removes the temporary files in `directory` that isAbandonedTemporaryFile proves abandoned (a
// process killed while writing). Writes call it for their target's directory. Never throws.
void removeStaleTemporaryFiles(const std::filesystem::path& directory);

// Throws std::runtime_error("cannot write <what> '<path>': <why>") unless a file can be created
// beside `path`, `path` is not a directory and it is none of the process's inputs (inputFileClash):
// what would fail a write at the end of a render, checked before it starts.
void checkWritable(const std::filesystem::path& path, const std::string& what);

}  // namespace lucent
