// lucent merge's work without its files: the parts of a split render read, checked to belong
// together (the same method, options, scene, version and instruction sets, each part complete, every
// pixel of their bounding box covered by the same samples exactly once) and added up. Exact film
// sums make the result the single render's wherever the parts' samples are the single render's.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "lucent/pipeline/film_file.h"

namespace lucent {

// A part as given: its film file, or its image with OUT.film beside it.
std::string partFilmPath(const std::string& part);

struct MergedFilm {
  std::unique_ptr<Film> film;
  FilmFileInfo info;  // the first part's, with the merged samples, counters summed, complete
  bool whole = false; // every pixel of the image, every sample of the render
  PixelRect box;      // the parts' bounding box
};
// Throws std::invalid_argument (or std::runtime_error for an unreadable part) naming the part and
// what keeps the parts from belonging together.
MergedFilm mergeFilmFiles(const std::vector<std::string>& parts);

}  // namespace lucent
