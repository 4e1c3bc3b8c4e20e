// libFuzzer target for the film file reader (docs/film-format.md): one input is one film file, as
// it is or with its size and hash made to match its header (film_fuzz_input.h). Every rejection
// must be a std::runtime_error or std::invalid_argument naming the file; anything else, a crash, a
// sanitizer report, a hang or a large allocation is a defect. Seeds: scripts/fuzz-corpus.py film_reader.
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "film_fuzz_input.h"
#include "fuzz_files.h"
#include "lucent/core/memory.h"
#include "lucent/pipeline/film_file.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  lucent::setMemoryLimit(lucent::memoryInUse() + (uint64_t(1) << 30));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = lucent::fuzz::scratchDirectory() / "part.film";
  lucent::fuzz::writeFile(path, lucent::fuzz::filmFileFromInput({reinterpret_cast<const char*>(data), size}));
  try {
    const lucent::FilmFile film = lucent::readFilmFile(path.string());
    (void)film.film->image();
  } catch (const std::runtime_error& e) {
    if (std::string_view(e.what()).find(path.string()) == std::string_view::npos) __builtin_trap();
  }
  return 0;
}
