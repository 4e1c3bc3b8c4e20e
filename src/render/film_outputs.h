// What `render` and `merge` write beside their images: film files (pipeline/film_file.h) and the
// EXR header of an image made from a film.
#pragma once
#include <string>

#include "lucent/image/image.h"
#include "lucent/pipeline/film_file.h"

namespace lucent {

// OUT.exr -> OUT.film, the film file of a render's or a merge's output.
std::string filmPathFor(const std::string& exrPath);

// The camera samples that every pixel of the film has taken.
uint32_t samplesEveryPixelHas(const Film& film);

// The image's metadata: method, options, derived values, seed, the samples per pixel that every
// pixel has (samplesEveryPixelHas), version,
// instruction sets, scene and its hash; for a part of a render (a crop or a sample range), also
// lucent:crop "x0,y0,x1,y1" and lucent:samples "FIRST:COUNT"; for an interrupted one,
// lucent:partial "true".
ImageMetadata filmMetadata(const FilmFileInfo& info, const Film& film);

// The first difference between the renders two film files are of (method, scene, options, version,
// instruction sets; not the part), as "its --seed is 3, this render's 4", or "" if none.
std::string renderDifference(const FilmFileInfo& film, const FilmFileInfo& other);

// The seed in a method's options JSON ("0" if it has none).
std::string seedOf(const std::string& optionsJson);

}  // namespace lucent
