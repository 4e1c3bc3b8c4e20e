// lucent merge PART.film|PART.exr... -o OUT.exr [--png OUT.png]
// Adds up the films of the parts of a split render (render --crop, --samples) into one image, once
// it has checked that they belong together: the same method, options (seed included), scene,
// version and instruction sets, each part complete, and every pixel of their bounding box covered
// by the same samples exactly once. Film sums are exact, so the merge is the single render's image
// wherever the parts' samples are the single render's. When the parts make up less than the whole
// image or less than all its samples, the merge is itself a part: OUT.film is written beside the
// image. Exit status: 0, or 1 with a message.
#include <algorithm>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>

#include "cli/commands.h"
#include "cli/film_outputs.h"
#include "cli/output_paths.h"
#include "lucent/core/memory.h"

namespace lucent::cli {

namespace {

struct MergeArgs {
  std::vector<std::string> parts;
  std::string output, png;
};

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

int runMerge(const MergeArgs& a) {
  const std::string filmPath = filmPathFor(a.output);
  std::vector<std::string> inputs = a.parts;
  for (const std::string& part : a.parts)
    if (std::filesystem::path(part).extension() == ".exr") inputs.push_back(filmPathFor(part));
  checkOutputFile(a.output, ".exr", "-o", inputs);
  if (!a.png.empty()) checkOutputFile(a.png, ".png", "--png", inputs);
  checkOutputFile(filmPath, ".film", "-o (its film file)", inputs);

  std::vector<FilmFile> films;
  for (const std::string& path : a.parts) {
    if (path.size() > 4 && path.substr(path.size() - 4) == ".exr" && std::filesystem::exists(filmPathFor(path))) {
      films.push_back(readFilmFile(filmPathFor(path)));
    } else {
      films.push_back(readFilmFile(path));
    }
    const FilmFile& f = films.back();
    if (!f.info.complete)
      throw std::invalid_argument("'" + path + "' is the checkpoint of an interrupted render: finish it first (render ... --resume)");
    const std::string difference = renderDifference(f.info, films.front().info);
    if (!difference.empty())
      throw std::invalid_argument("'" + path + "' and '" + a.parts.front() + "' are parts of different renders: " + difference);
    const Film &film = *f.film, &first = *films.front().film;
    if (film.imageWidth() != first.imageWidth() || film.imageHeight() != first.imageHeight() ||
        film.sums() != first.sums() || !(film.layers() == first.layers()))
      throw std::invalid_argument("'" + path + "' and '" + a.parts.front() + "' are films of different layouts");
  }
  PixelRect box = films.front().film->region();
  for (const FilmFile& f : films) {
    const PixelRect& r = f.film->region();
    box = {std::min(box.x0, r.x0), std::min(box.y0, r.y0), std::max(box.x1, r.x1), std::max(box.y1, r.y1)};
  }
  const auto [firstSample, sampleCount] = commonSamples(a.parts, films, box);

  const Film& model = *films.front().film;
  const int width = model.imageWidth(), height = model.imageHeight();
  Film merged(width, height, box, model.sums(), model.layers());
  FilmFileInfo info = films.front().info;
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
  const bool whole = box == PixelRect{0, 0, width, height} && firstSample == 0 &&
                     sampleCount == info.spp;
  ImageMetadata meta = filmMetadata(info, merged);
  meta.emplace_back("lucent:merged_parts", std::to_string(a.parts.size()));
  std::vector<FileToWrite> alsoWrite;
  if (!whole) alsoWrite.push_back(filmFile(filmPath, merged, info));
  writeExrAndPng(merged.image(), a.output, meta, a.png, std::move(alsoWrite));

  nlohmann::ordered_json summary;
  summary["method"] = info.method;
  summary["options"] = nlohmann::ordered_json::parse(info.options);
  summary["merged_parts"] = a.parts.size();
  summary["crop"] = {box.x0, box.y0, box.x1, box.y1};
  summary["samples"] = {firstSample, sampleCount};
  summary["whole"] = whole;
  for (const auto& [name, value] : info.counters) summary["counters"][name] = value;
  summary["output"] = a.output;
  if (!a.png.empty()) summary["png"] = a.png;
  if (!whole) summary["film"] = filmPath;
  summary["scene_hash"] = info.sceneHash;
  std::cout << summary.dump() << std::endl;
  return 0;
}

}  // namespace

void addMergeCommand(CLI::App& app, int& exitCode) {
  auto args = std::make_shared<MergeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "merge", "Merge the film files of the parts of a split render (render --crop, --samples) into one image");
  cmd->add_option("parts", args->parts, "The parts' film files, or their images with their OUT.film beside them")
      ->required();
  cmd->add_option("-o,--output", args->output, "Output EXR file")->required();
  cmd->add_option("--png", args->png, "Also write an sRGB PNG");
  cmd->callback([args, &exitCode] { exitCode = runMerge(*args); });
}

}  // namespace lucent::cli
