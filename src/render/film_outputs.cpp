#include "render/film_outputs.h"

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "lucent/methods/methods.h"
#include "lucent/trace/visibility.h"

namespace lucent {

std::string filmPathFor(const std::string& exrPath) {
  return std::filesystem::path(exrPath).replace_extension(".film").string();
}

std::string seedOf(const std::string& optionsJson) {
  const auto options = nlohmann::json::parse(optionsJson.empty() ? "{}" : optionsJson);
  return options.contains("seed") ? options["seed"].dump() : "0";
}

std::string renderDifference(const FilmFileInfo& film, const FilmFileInfo& other) {
  if (film.method != other.method) return "it is of --method " + film.method + ", this render of " + other.method;
  if (film.sceneHash != other.sceneHash)
    return "it is of another scene or resolution (scene hash " + film.sceneHash + ", this render's " + other.sceneHash + ")";
  const auto a = nlohmann::json::parse(film.options), b = nlohmann::json::parse(other.options);
  const auto& specs = renderingMethod(other.method).options();
  auto spec = [&](const std::string& name) {
    OptionSpec named;
    named.name = name;
    for (const OptionSpec& s : specs)
      if (s.name == name) return s;
    return named;  // an option the method no longer declares: it may change the image
  };
  for (const auto& [name, value] : b.items())
    if (spec(name).changesImage && (!a.contains(name) || a[name] != value))
      return "its " + spec(name).flag() + " is " + (a.contains(name) ? a[name].dump() : "not set") + ", this render's " +
             value.dump();
  if (film.version != other.version) return "it was rendered by Lucent " + film.version + ", this render by " + other.version;
  if (film.embreeIsa != other.embreeIsa || film.laneIsa != other.laneIsa)
    return "it was rendered with --isa " + film.embreeIsa + " (lanes " + film.laneIsa + "), this render with " +
           other.embreeIsa + " (lanes " + other.laneIsa + "): images differ across Embree's instruction sets";
  return "";
}

uint32_t samplesEveryPixelHas(const Film& film) {
  const auto taken = film.samplesTaken();
  return *std::min_element(taken.begin(), taken.end());
}

ImageMetadata filmMetadata(const FilmFileInfo& info, const Film& film) {
  ImageMetadata meta = {{"lucent:method", info.method},
                        {"lucent:options", info.options},
                        {"lucent:derived", info.derived.empty() ? "{}" : info.derived},
                        {"lucent:spp", std::to_string(samplesEveryPixelHas(film))},
                        {"lucent:seed", seedOf(info.options)},
                        {"lucent:version", info.version},
                        {"lucent:embree_version", Visibility::embreeVersion()},
                        {"lucent:embree_isa", info.embreeIsa},
                        {"lucent:lane_isa", info.laneIsa},
                        {"lucent:scene", info.scene},
                        {"lucent:scene_hash", info.sceneHash}};
  const PixelRect& r = film.region();
  if (!(r == PixelRect{0, 0, film.imageWidth(), film.imageHeight()}))
    meta.emplace_back("lucent:crop", std::to_string(r.x0) + "," + std::to_string(r.y0) + "," + std::to_string(r.x1) +
                                         "," + std::to_string(r.y1));
  if (info.firstSample != 0 || info.sampleCount != info.spp)
    meta.emplace_back("lucent:samples", std::to_string(info.firstSample) + ":" + std::to_string(info.sampleCount));
  if (!info.complete) meta.emplace_back("lucent:partial", "true");
  if (film.layers().features) meta.emplace_back("lucent:materials", nlohmann::json(film.materialNames()).dump());
  return meta;
}

}  // namespace lucent
