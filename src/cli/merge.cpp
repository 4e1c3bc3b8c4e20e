// lucent merge PART.film|PART.exr... -o OUT.exr [--png OUT.png]
// Adds up the films of the parts of a split render (render --crop, --samples) into one image, once
// it has checked that they belong together: the same method, options (seed included), scene,
// version and instruction sets, each part complete, and every pixel of their bounding box covered
// by the same samples exactly once. Film sums are exact, so the merge is the single render's image
// wherever the parts' samples are the single render's. When the parts make up less than the whole
// image or less than all its samples, the merge is itself a part: OUT.film is written beside the
// image. Exit status: 0, or 1 with a message.
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "render/film_merge.h"
#include "render/film_outputs.h"
#include "render/output_paths.h"
#include "core/json_text.h"

namespace lucent::cli {

namespace {

struct MergeArgs {
  std::vector<std::string> parts;
  std::string output, png;
};

int runMerge(const MergeArgs& a) {
  const std::string filmPath = filmPathFor(a.output);
  std::vector<std::string> inputs = a.parts;
  for (const std::string& part : a.parts)
    if (std::filesystem::path(part).extension() == ".exr") inputs.push_back(filmPathFor(part));
  checkOutputFile(a.output, ".exr", "-o", inputs);
  if (!a.png.empty()) checkOutputFile(a.png, ".png", "--png", inputs);
  checkOutputFile(filmPath, ".film", "-o (its film file)", inputs);

  const MergedFilm merged = mergeFilmFiles(a.parts);
  const FilmFileInfo& info = merged.info;
  const PixelRect& box = merged.box;
  const bool whole = merged.whole;
  ImageMetadata meta = filmMetadata(info, *merged.film);
  meta.emplace_back("lucent:merged_parts", std::to_string(a.parts.size()));
  std::vector<FileToWrite> alsoWrite;
  if (!whole) alsoWrite.push_back(filmFile(filmPath, *merged.film, info));
  writeExrAndPng(merged.film->image(), a.output, meta, a.png, std::move(alsoWrite));

  nlohmann::ordered_json summary;
  summary["method"] = info.method;
  summary["options"] = nlohmann::ordered_json::parse(info.options);
  summary["merged_parts"] = a.parts.size();
  summary["crop"] = {box.x0, box.y0, box.x1, box.y1};
  summary["samples"] = {info.firstSample, info.sampleCount};
  summary["whole"] = whole;
  for (const auto& [name, value] : info.counters) summary["counters"][name] = value;
  summary["output"] = a.output;
  if (!a.png.empty()) summary["png"] = a.png;
  if (!whole) summary["film"] = filmPath;
  summary["scene_hash"] = info.sceneHash;
  std::cout << jsonText(summary) << std::endl;
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
