// Film files from fuzz inputs, for the film reader and merge targets. An input whose first byte is
// even is a film file as it is (an attacker's bytes: most fail the hash); an odd one is a header's
// JSON, a NUL, then the arrays' bytes, written as a film file whose size and hash match what the
// header describes (docs/film-format.md), so that the header's checks and the arrays' are reached.
#pragma once
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace lucent::fuzz {

struct Fnv1a {
  uint64_t value = 0xcbf29ce484222325ull;
  void add(std::string_view bytes) {
    for (size_t i = 0; i < bytes.size(); i += 8) {
      uint64_t word = 0;
      std::memcpy(&word, bytes.data() + i, std::min<size_t>(8, bytes.size() - i));
      value = (value ^ word) * 0x100000001b3ull;
    }
  }
};

inline std::string filmFileFromInput(std::string_view input) {
  if (input.empty() || (static_cast<unsigned char>(input[0]) & 1) == 0) return std::string(input.substr(input.empty() ? 0 : 1));
  input.remove_prefix(1);
  const size_t nul = std::min(input.find('\0'), input.size());
  std::string header(input.substr(0, nul));
  const std::string_view arrays = nul < input.size() ? input.substr(nul + 1) : std::string_view();
  // The arrays' sizes as the header gives them, where it gives them plausibly; else as they come.
  uint64_t pixels = 0, sums = 0;
  bool features = false;  // a third array, the pixels' surfaces
  try {
    const auto j = nlohmann::json::parse(header);
    const auto& crop = j.at("crop");
    const auto small = [](const nlohmann::json& v) {  // a whole number the reader would take
      if (!v.is_number_integer()) return false;
      return v.is_number_unsigned() ? v.get<uint64_t>() <= 65536 : v.get<int64_t>() >= 0 && v.get<int64_t>() <= 65536;
    };
    if (small(crop.at(0)) && small(crop.at(1)) && small(crop.at(2)) && small(crop.at(3)) && small(j.at("sums_per_pixel"))) {
      const int64_t w = crop[2].get<int64_t>() - crop[0].get<int64_t>();
      const int64_t h = crop[3].get<int64_t>() - crop[1].get<int64_t>();
      const int64_t s = j["sums_per_pixel"].get<int64_t>();
      if (w > 0 && h > 0 && s > 0 && w * h <= (1 << 16) && s <= 64) pixels = uint64_t(w * h), sums = uint64_t(s);
    }
    const auto& layers = j.at("layers");
    features = layers.is_object() && layers.contains("features") && layers["features"] == true;
  } catch (const nlohmann::json::exception&) {
  }
  header.resize((header.size() + 7) / 8 * 8, ' ');
  std::string sumBytes, valid, taken, surfaces;
  if (pixels > 0) {
    sumBytes.assign(pixels * sums * 24, '\0'), valid.assign(pixels * 4, '\0'), taken.assign(pixels * 4, '\0');
    if (features) surfaces.assign(pixels * 4, '\0');
    size_t at = 0;
    for (std::string* array : {&sumBytes, &valid, &taken, &surfaces}) {
      const size_t n = std::min(array->size(), arrays.size() > at ? arrays.size() - at : 0);
      if (n > 0) std::memcpy(array->data(), arrays.data() + at, n);
      at += n;
    }
  } else {
    sumBytes.assign(arrays);
  }
  Fnv1a hash;
  hash.add(header), hash.add(sumBytes), hash.add(valid), hash.add(taken), hash.add(surfaces);
  std::string file = "LCNTFILM";
  const uint32_t version = 4, headerBytes = uint32_t(header.size());
  file.append(reinterpret_cast<const char*>(&version), 4);
  file.append(reinterpret_cast<const char*>(&headerBytes), 4);
  file.append(reinterpret_cast<const char*>(&hash.value), 8);
  file += header + sumBytes;
  for (std::string* counts : {&valid, &taken, &surfaces}) {
    counts->resize((counts->size() + 7) / 8 * 8, '\0');
    file += *counts;
  }
  return file;
}

}  // namespace lucent::fuzz
