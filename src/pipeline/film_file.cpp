#include "lucent/pipeline/film_file.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/json_text.h"
#include "lucent/core/files.h"
#include "lucent/core/memory.h"

namespace lucent {

namespace {

constexpr char kFilmMagic[8] = {'L', 'C', 'N', 'T', 'F', 'I', 'L', 'M'};
constexpr uint32_t kFormatVersion = 4;
constexpr uint32_t kPreambleBytes = 24;  // magic, version, header size, hash
constexpr uint32_t kMaxHeaderBytes = 1 << 20;

// FNV-1a over the header and the arrays as 64-bit little-endian words, each array's last word
// zero-filled: the format's hash.
struct DataHash {
  uint64_t value = 0xcbf29ce484222325ull;
  void add(const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; i += 8) {
      uint64_t word = 0;  // the last word's missing bytes are the padding's zeros
      std::memcpy(&word, p + i, std::min<size_t>(8, bytes - i));
      value = (value ^ word) * 0x100000001b3ull;
    }
  }
};

// The count arrays (32-bit words) are padded to 8 bytes: every array starts 8-byte aligned.
size_t padded(size_t bytes) { return (bytes + 7) / 8 * 8; }

}  // namespace

FileToWrite filmFile(const std::string& path, const Film& film, const FilmFileInfo& info) {
  const auto sums = film.pixelSums();
  const auto valid = film.validSamples(), taken = film.samplesTaken(), surfaces = film.pixelSurfaces();
  const size_t countBytes = padded(valid.size_bytes());

  nlohmann::ordered_json header;
  header["method"] = info.method;
  header["options"] = nlohmann::json::parse(info.options.empty() ? "{}" : info.options);
  header["derived"] = nlohmann::json::parse(info.derived.empty() ? "{}" : info.derived);
  header["scene"] = info.scene;
  header["scene_hash"] = info.sceneHash;
  header["version"] = info.version;
  header["embree_isa"] = info.embreeIsa;
  header["lane_isa"] = info.laneIsa;
  header["width"] = film.imageWidth();
  header["height"] = film.imageHeight();
  const PixelRect& r = film.region();
  header["crop"] = {r.x0, r.y0, r.x1, r.y1};
  header["spp"] = info.spp;
  header["first_sample"] = info.firstSample;
  header["sample_count"] = info.sampleCount;
  header["complete"] = info.complete;
  header["sums"] = film.sums() == Film::Sums::PerSample ? "per_sample" : "per_part";
  header["layers"] = {{"features", film.layers().features}, {"caustic", film.layers().caustic},
                      {"variance", film.layers().variance}, {"paths", film.layers().paths}};
  header["sums_per_pixel"] = film.sumsPerPixel();
  if (film.layers().features) header["materials"] = film.materialNames();
  header["counters"] = nlohmann::ordered_json::object();
  for (const auto& [name, value] : info.counters) header["counters"][name] = value;
  std::string text = jsonText(header);
  text.resize(padded(text.size()), ' ');
  DataHash hash;
  hash.add(text.data(), text.size());
  hash.add(sums.data(), sums.size_bytes());
  hash.add(valid.data(), valid.size_bytes());
  hash.add(taken.data(), taken.size_bytes());
  hash.add(surfaces.data(), surfaces.size_bytes());

  return {path, "film", [&film, text, countBytes, fileHash = hash.value](const std::filesystem::path& tmp) {
            const auto sums = film.pixelSums();
            const auto valid = film.validSamples(), taken = film.samplesTaken(), surfaces = film.pixelSurfaces();
            const uint64_t zeros = 0;
            std::ofstream out(tmp, std::ios::binary);
            const uint32_t version = kFormatVersion, headerBytes = uint32_t(text.size());
            out.write(kFilmMagic, 8);
            out.write(reinterpret_cast<const char*>(&version), 4);
            out.write(reinterpret_cast<const char*>(&headerBytes), 4);
            out.write(reinterpret_cast<const char*>(&fileHash), 8);
            out.write(text.data(), std::streamsize(text.size()));
            out.write(reinterpret_cast<const char*>(sums.data()), std::streamsize(sums.size_bytes()));
            for (const auto& counts : {valid, taken, surfaces}) {
              if (counts.empty()) continue;
              out.write(reinterpret_cast<const char*>(counts.data()), std::streamsize(counts.size_bytes()));
              out.write(reinterpret_cast<const char*>(&zeros), std::streamsize(countBytes - counts.size_bytes()));
            }
            if (!out.flush()) throw WriteFailure("write failed (disk full?)");
          }};
}

void writeFilmFile(const std::string& path, const Film& film, const FilmFileInfo& info) {
  writeFilesAtomically({filmFile(path, film, info)});
}

namespace {

using Failure = std::function<std::runtime_error(const std::string&)>;

// What a film file's header says of the film it holds.
struct FilmHeader {
  FilmFileInfo info;
  int width = 0, height = 0, sumsPerPixel = 0;
  PixelRect region;
  Film::Sums sums = Film::Sums::PerSample;
  FilmLayers layers;
  std::vector<std::string> materialNames;
};

// Whole numbers checked against their range before they are narrowed: a header's numbers are read
// as written, never wrapped. (nlohmann reads every integer of at least 0 as unsigned: both bounds
// apply to both kinds.)
int headerInteger(const nlohmann::json& value, const std::string& key, int64_t min, int64_t max, const Failure& fail) {
  const bool inRange = value.is_number_unsigned()
                           ? value.get<uint64_t>() <= uint64_t(max) && (min <= 0 || value.get<uint64_t>() >= uint64_t(min))
                           : value.is_number_integer() && value.get<int64_t>() >= min && value.get<int64_t>() <= max;
  if (!inRange)
    throw fail("header: '" + key + "' is not a whole number in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  return int(value.get<int64_t>());
}

// The render the film is of: method, options, scene, version, instruction sets, samples, counters.
FilmFileInfo renderInfo(const nlohmann::json& header, const Failure& fail) {
  constexpr int64_t kMaxSamples = int64_t(1) << 24;  // render's --spp bound
  FilmFileInfo info;
  info.method = header.at("method").get<std::string>();
  for (const char* key : {"options", "derived", "counters", "layers"})
    if (!header.at(key).is_object()) throw fail(std::string("header: '") + key + "' is not a JSON object");
  info.options = header.at("options").dump();
  info.derived = header.at("derived").dump();
  info.scene = header.at("scene").get<std::string>();
  info.sceneHash = header.at("scene_hash").get<std::string>();
  info.version = header.at("version").get<std::string>();
  info.embreeIsa = header.at("embree_isa").get<std::string>();
  info.laneIsa = header.at("lane_isa").get<std::string>();
  info.spp = headerInteger(header.at("spp"), "spp", 1, kMaxSamples, fail);
  info.firstSample = headerInteger(header.at("first_sample"), "first_sample", 0, kMaxSamples - 1, fail);
  info.sampleCount = headerInteger(header.at("sample_count"), "sample_count", 1, kMaxSamples, fail);
  info.complete = header.at("complete").get<bool>();
  for (const auto& [name, value] : header.at("counters").items()) {
    if (!value.is_number_unsigned() && !(value.is_number_integer() && value.get<int64_t>() >= 0))
      throw fail("header: counter '" + name + "' is not a whole number of at least 0");
    info.counters.emplace_back(name, value.get<uint64_t>());
  }
  return info;
}

FilmHeader parseFilmHeader(const std::string& text, const Failure& fail) {
  FilmHeader h;
  try {
    const nlohmann::json header = nlohmann::json::parse(text);
    if (!header.is_object()) throw fail("header: not a JSON object");
    h.info = renderInfo(header, fail);
    h.width = headerInteger(header.at("width"), "width", 1, 65536, fail);
    h.height = headerInteger(header.at("height"), "height", 1, 65536, fail);
    const nlohmann::json& crop = header.at("crop");
    if (!crop.is_array() || crop.size() != 4) throw fail("'crop' is not [x0, y0, x1, y1]");
    h.region = {headerInteger(crop[0], "crop", 0, 65536, fail), headerInteger(crop[1], "crop", 0, 65536, fail),
                headerInteger(crop[2], "crop", 0, 65536, fail), headerInteger(crop[3], "crop", 0, 65536, fail)};
    const std::string sumsName = header.at("sums").get<std::string>();
    if (sumsName != "per_sample" && sumsName != "per_part") throw fail("unknown 'sums' '" + sumsName + "'");
    h.sums = sumsName == "per_sample" ? Film::Sums::PerSample : Film::Sums::PerPart;
    h.layers.features = header.at("layers").at("features").get<bool>();
    h.layers.caustic = header.at("layers").at("caustic").get<bool>();
    h.layers.variance = header.at("layers").at("variance").get<bool>();
    // Files from before the light split by path have no "paths".
    h.layers.paths = header.at("layers").contains("paths") && header.at("layers").at("paths").get<bool>();
    if (h.layers.variance && h.sums != Film::Sums::PerSample) throw fail("a 'variance' layer needs 'per_sample' sums");
    if (h.layers.paths && h.sums != Film::Sums::PerSample) throw fail("a 'paths' layer needs 'per_sample' sums");
    h.sumsPerPixel = headerInteger(header.at("sums_per_pixel"), "sums_per_pixel", 1, 256, fail);
    if (h.layers.features) {
      const nlohmann::json& names = header.at("materials");
      if (!names.is_array()) throw fail("header: 'materials' is not an array of names");
      for (const nlohmann::json& name : names) h.materialNames.push_back(name.get<std::string>());
    }
  } catch (const nlohmann::json::exception& e) {
    throw fail(std::string("header: ") + e.what());
  }
  if (uint64_t(h.width) * uint64_t(h.height) > (uint64_t(1) << 26))
    throw fail("image of " + std::to_string(h.width) + " x " + std::to_string(h.height) + " pixels");
  if (h.region.empty() || !PixelRect{0, 0, h.width, h.height}.contains(h.region)) throw fail("'crop' is not inside the image");
  if (int64_t(h.info.firstSample) + int64_t(h.info.sampleCount) > int64_t(h.info.spp))
    throw fail("samples " + std::to_string(h.info.firstSample) + ":" + std::to_string(h.info.sampleCount) + " of " +
               std::to_string(h.info.spp));
  // Its sums per pixel are the ones its sums and layers make (a film of one pixel tells).
  if (Film(1, 1, {0, 0, 1, 1}, h.sums, h.layers).sumsPerPixel() != h.sumsPerPixel)
    throw fail("'sums_per_pixel' does not match its sums and layers");
  return h;
}

// The counts a film's pixels hold agree with its part and its materials.
void checkPixelCounts(const Film& film, const FilmFileInfo& info, const Failure& fail) {
  const auto valid = film.validSamples(), taken = film.samplesTaken(), surfaces = film.pixelSurfaces();
  for (uint32_t t : taken) {
    if (t > uint32_t(info.sampleCount)) throw fail("a pixel has taken more samples than the part has");
    if (info.complete && t != uint32_t(info.sampleCount))
      throw fail("it says it is complete, but a pixel has taken fewer samples than the part has");
  }
  for (size_t i = 0; i < valid.size(); ++i)
    if (valid[i] > taken[i]) throw fail("a pixel has more valid samples than it took");
  // A render traces its pixels' surfaces before any sample: every film of one knows them all.
  const int materials = int(film.materialNames().size());
  for (uint32_t code : surfaces)
    if (code == PixelSurface::kUnknown || PixelSurface::material(code) < -1 || PixelSurface::material(code) >= materials)
      throw fail("a pixel's surface is not the background or one of its " + std::to_string(materials) + " materials");
}

}  // namespace

FilmFile readFilmFile(const std::string& path) {
  const Failure fail = [&](const std::string& why) { return std::runtime_error("film file '" + path + "': " + why); };
  // Not admitted as an input (core/files.h): a film is a render's own state, which its checkpoints
  // replace; merge names its parts as inputs itself.
  const std::string problem = regularFileProblem(path);
  if (!problem.empty()) throw fail(problem);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw fail("cannot be opened");
  char magic[8];
  uint32_t version = 0, headerBytes = 0;
  uint64_t fileHash = 0;
  in.read(magic, 8);
  in.read(reinterpret_cast<char*>(&version), 4);
  if (!in || std::memcmp(magic, kFilmMagic, 8) != 0) throw fail("not a Lucent film file");
  if (version != kFormatVersion)
    throw fail("format version " + std::to_string(version) + "; this Lucent reads version " + std::to_string(kFormatVersion));
  in.read(reinterpret_cast<char*>(&headerBytes), 4);
  in.read(reinterpret_cast<char*>(&fileHash), 8);
  if (!in) throw fail("truncated header");
  if (headerBytes > kMaxHeaderBytes || headerBytes % 8 != 0)
    throw fail("header of " + std::to_string(headerBytes) + " bytes (at most 2^20, a multiple of 8)");
  std::error_code ec;
  const uintmax_t fileBytes = std::filesystem::file_size(path, ec);
  if (ec || fileBytes < uintmax_t(kPreambleBytes) + headerBytes) throw fail("truncated header");
  std::string text(headerBytes, ' ');
  in.read(text.data(), headerBytes);
  if (!in) throw fail("truncated header");
  FilmHeader header = parseFilmHeader(text, fail);

  // The file's size bounds what is allocated: a header cannot ask for more than the file holds.
  const uint64_t pixels = header.region.pixelCount();
  const uint64_t sumBytes = pixels * uint64_t(header.sumsPerPixel) * sizeof(ExactSum), countBytes = padded(pixels * 4);
  const uint64_t countArrays = header.layers.features ? 3 : 2;  // valid, taken, and with features the pixels' surfaces
  const uint64_t expected = kPreambleBytes + uint64_t(headerBytes) + sumBytes + countArrays * countBytes;
  if (fileBytes != expected)
    throw fail("its size is not the " + std::to_string(expected) + " bytes its header makes (truncated or damaged)");
  requireMemory(pixels * (uint64_t(header.sumsPerPixel) * sizeof(ExactSum) + 4 * countArrays),
                "the film of '" + path + "'", "raise --memory-limit if the machine has the memory");
  FilmFile file;
  file.info = std::move(header.info);
  file.film = std::make_unique<Film>(header.width, header.height, header.region, header.sums, header.layers);
  Film& film = *file.film;
  const auto sumsData = film.pixelSums();
  if (header.layers.features) film.setMaterialNames(std::move(header.materialNames));
  const auto valid = film.validSamples(), taken = film.samplesTaken(), surfaces = film.pixelSurfaces();
  in.read(reinterpret_cast<char*>(sumsData.data()), std::streamsize(sumsData.size_bytes()));
  std::vector<char> padding(8);
  for (const auto& counts : {valid, taken, surfaces}) {
    if (counts.empty()) continue;
    in.read(reinterpret_cast<char*>(counts.data()), std::streamsize(counts.size_bytes()));
    in.read(padding.data(), std::streamsize(countBytes - counts.size_bytes()));
  }
  if (!in) throw fail("truncated data");
  DataHash hash;
  hash.add(text.data(), text.size());
  hash.add(sumsData.data(), sumsData.size_bytes());
  hash.add(valid.data(), valid.size_bytes());
  hash.add(taken.data(), taken.size_bytes());
  hash.add(surfaces.data(), surfaces.size_bytes());
  if (hash.value != fileHash) throw fail("its header or data does not match its hash (damaged)");
  checkPixelCounts(film, file.info, fail);
  return file;
}

}  // namespace lucent
