// Film files (docs/film-format.md): a film's exact sums, valid samples and samples taken per pixel,
// with what it is a film of (method, options, scene, version, instruction sets, part). A render
// writes one as a checkpoint (--checkpoint, a stop request) and as the result of a part of a split
// render (--crop, --samples); --resume continues one and `lucent merge` adds parts up.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lucent/core/files.h"
#include "lucent/pipeline/film.h"

namespace lucent {

struct FilmFileInfo {
  std::string method;
  std::string options;  // the method's resolved options, as the JSON object that lucent:options holds
  std::string derived;  // the values the method derived (lucent:derived)
  std::string scene;    // the scene file's path
  std::string sceneHash;
  std::string version;  // Lucent's
  std::string embreeIsa, laneIsa;
  int spp = 0;          // camera samples per pixel of the whole render
  int firstSample = 0, sampleCount = 0;  // the part's samples of each pixel
  bool complete = false;  // every pixel of the part has all its samples (not a checkpoint)
  std::vector<std::pair<std::string, uint64_t>> counters;  // the work the film's samples took
};

// The film file as one of a set of files written as one (writeFilesAtomically; the EXR of the same
// render beside it). The film and info must outlive the write.
FileToWrite filmFile(const std::string& path, const Film& film, const FilmFileInfo& info);
// Writes the film and its info whole or not at all (a temporary file, then a rename); throws
// std::runtime_error naming the file when it cannot.
void writeFilmFile(const std::string& path, const Film& film, const FilmFileInfo& info);

struct FilmFile {
  FilmFileInfo info;
  std::unique_ptr<Film> film;
};
// Reads and checks a film file (its magic, format version, header, sizes and data hash); throws
// std::runtime_error naming the file and what is wrong.
FilmFile readFilmFile(const std::string& path);

}  // namespace lucent
