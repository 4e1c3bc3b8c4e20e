// The files a command was asked to write, checked before it does any work: what would otherwise
// fail only at the end, after a render's whole time was spent.
#pragma once
#include <string>
#include <vector>

namespace lucent {

// Throws std::invalid_argument naming `flag` unless `path` ends in `extension`, its directory exists,
// it is none of `inputs` (the files the command reads, perhaps not read yet) nor of the files the
// process has read (core/files.h's inputFileClash, by identity) and a file can be created beside it
// (core/files.h's checkWritable: permissions, a read-only file system, a name too long, a directory
// in its place).
void checkOutputFile(const std::string& path, const std::string& extension, const std::string& flag,
                     const std::vector<std::string>& inputs);

}  // namespace lucent
