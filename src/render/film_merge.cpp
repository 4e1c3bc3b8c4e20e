#include "render/film_merge.h"

#include <algorithm>
#include <filesystem>
#include <optional>
#include <set>
#include <stdexcept>

#include "render/film_outputs.h"

namespace lucent {

namespace {

std::string rectText(const PixelRect& r) {
  return std::to_string(r.x0) + "," + std::to_string(r.y0) + "," + std::to_string(r.x1) + "," + std::to_string(r.y1);
}

// The samples [first, first + count) every pixel of the parts' bounding box has from the parts,
// once each; throws naming the pixels and parts where that is not so.
std::pair<int, int> commonSamples(const std::vector<std::string>& paths, const std::vector<FilmFile>& films,
                                  const PixelRect& box) {
  // Coverage is constant between the parts' edges: one check per cell of the grid they make.
  std::set<int> xs = {box.x0, box.x1}, ys = {box.y0, box.y1};
  for (const FilmFile& f : films) {
    const PixelRect& r = f.film->region();
    xs.insert({r.x0, r.x1}), ys.insert({r.y0, r.y1});
  }
  const std::vector<int> xv(xs.begin(), xs.end()), yv(ys.begin(), ys.end());
  std::optional<std::pair<int, int>> common;
  for (size_t j = 0; j + 1 < yv.size(); ++j)
    for (size_t i = 0; i + 1 < xv.size(); ++i) {
      const PixelRect cell{xv[i], yv[j], xv[i + 1], yv[j + 1]};
      std::vector<std::pair<int, size_t>> ranges;  // first sample, part
      for (size_t p = 0; p < films.size(); ++p)
        if (films[p].film->region().contains(cell)) ranges.emplace_back(films[p].info.firstSample, p);
      std::sort(ranges.begin(), ranges.end());
      if (ranges.empty()) throw std::invalid_argument("no part has the pixels " + rectText(cell));
      const int first = ranges[0].first;
      int end = first;
      for (const auto& [begin, p] : ranges) {
        const FilmFileInfo& info = films[p].info;
        if (begin < end)
          throw std::invalid_argument("'" + paths[p] + "' repeats samples another part has at the pixels " +
                                      rectText(cell) + " (its --samples " + std::to_string(info.firstSample) + ":" +
                                      std::to_string(info.sampleCount) + ")");
        if (begin > end)
          throw std::invalid_argument("no part has the samples " + std::to_string(end) + " to " +
                                      std::to_string(begin - 1) + " of the pixels " + rectText(cell));
        end = begin + info.sampleCount;
      }
      const std::pair<int, int> here{first, end - first};
      if (!common) common = here;
      if (*common != here)
        throw std::invalid_argument("the pixels " + rectText(cell) + " have the samples " + std::to_string(here.first) +
                                    ":" + std::to_string(here.second) + " from the parts, others " +
                                    std::to_string(common->first) + ":" + std::to_string(common->second));
    }
  return *common;
}

}  // namespace

std::string partFilmPath(const std::string& part) {
  if (part.size() > 4 && part.substr(part.size() - 4) == ".exr" && std::filesystem::exists(filmPathFor(part)))
    return filmPathFor(part);
  return part;
}

MergedFilm mergeFilmFiles(const std::vector<std::string>& parts) {
  if (parts.empty()) throw std::invalid_argument("no parts to merge");
  std::vector<FilmFile> films;
  for (const std::string& path : parts) {
    films.push_back(readFilmFile(partFilmPath(path)));
    const FilmFile& f = films.back();
    if (!f.info.complete)
      throw std::invalid_argument("'" + path + "' is the checkpoint of an interrupted render: finish it first (render ... --resume)");
    std::string difference;
    try {
      difference = renderDifference(f.info, films.front().info);
    } catch (const std::invalid_argument& e) {  // a method this Lucent does not have
      throw std::invalid_argument("'" + path + "': " + e.what());
    }
    if (!difference.empty())
      throw std::invalid_argument("'" + path + "' and '" + parts.front() + "' are parts of different renders: " + difference);
    const Film &film = *f.film, &first = *films.front().film;
    if (film.imageWidth() != first.imageWidth() || film.imageHeight() != first.imageHeight() ||
        film.sums() != first.sums() || !(film.layers() == first.layers()))
      throw std::invalid_argument("'" + path + "' and '" + parts.front() + "' are films of different layouts");
  }
  PixelRect box = films.front().film->region();
  for (const FilmFile& f : films) {
    const PixelRect& r = f.film->region();
    box = {std::min(box.x0, r.x0), std::min(box.y0, r.y0), std::max(box.x1, r.x1), std::max(box.y1, r.y1)};
  }
  const auto [firstSample, sampleCount] = commonSamples(parts, films, box);

  const Film& model = *films.front().film;
  const int width = model.imageWidth(), height = model.imageHeight();
  MergedFilm out{std::make_unique<Film>(width, height, box, model.sums(), model.layers()), films.front().info, false, box};
  Film& merged = *out.film;
  merged.setMaterialNames(model.materialNames());
  FilmFileInfo& info = out.info;
  info.firstSample = firstSample;
  info.sampleCount = sampleCount;
  info.complete = true;
  info.counters.clear();
  for (FilmFile& f : films) {
    merged.add(*f.film);
    for (const std::pair<std::string, uint64_t>& counter : f.info.counters) {
      auto it = std::find_if(info.counters.begin(), info.counters.end(),
                             [&](const auto& c) { return c.first == counter.first; });
      if (it == info.counters.end()) info.counters.push_back(counter);
      else it->second += counter.second;
    }
    f.film.reset();  // one part's memory at a time beside the merged film
  }
  out.whole = box == PixelRect{0, 0, width, height} && firstSample == 0 && sampleCount == info.spp;
  return out;
}

}  // namespace lucent
