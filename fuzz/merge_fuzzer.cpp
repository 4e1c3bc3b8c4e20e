// libFuzzer target for lucent merge's checks (src/cli/film_merge.h): one input is up to four parts'
// film files (each as film_fuzz_input.h makes it), separated by the line "--part--". Every
// rejection must be a std::invalid_argument or std::runtime_error; anything else, a crash, a
// sanitizer report, a hang or a large allocation is a defect. Seeds: scripts/fuzz-corpus.py merge.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "render/film_merge.h"
#include "film_fuzz_input.h"
#include "fuzz_files.h"
#include "lucent/core/memory.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  lucent::setMemoryLimit(lucent::memoryInUse() + (uint64_t(1) << 30));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view input(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view kSeparator = "\n--part--\n";
  std::vector<std::string> parts;
  while (parts.size() < 4) {
    const size_t end = std::min(input.find(kSeparator), input.size());
    const auto path = lucent::fuzz::scratchDirectory() / ("part" + std::to_string(parts.size()) + ".film");
    lucent::fuzz::writeFile(path, lucent::fuzz::filmFileFromInput(input.substr(0, end)));
    parts.push_back(path.string());
    if (end == input.size()) break;
    input.remove_prefix(end + kSeparator.size());
  }
  try {
    const lucent::MergedFilm merged = lucent::mergeFilmFiles(parts);
    (void)merged.film->image();
  } catch (const std::invalid_argument&) {
  } catch (const std::runtime_error&) {
  }
  return 0;
}
