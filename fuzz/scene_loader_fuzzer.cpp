// libFuzzer target for the scene loader: JSON, OBJ, MTL and the images it reads (a texture, an
// environment map). One input is a scene's files separated by NUL bytes: scene.json, mesh.obj,
// mesh.mtl, then one image, the rest of the input whatever NULs it holds, written both as
// texture.png and as sky.hdr (the image readers go by content where the name misleads). A missing
// part is a missing file. Every
// rejection must be a SceneError; anything else that escapes, a crash, a sanitizer report, a hang
// (-timeout) or a large allocation (-malloc_limit_mb) is a defect. Seeds: scripts/fuzz-corpus.py.
#include <cstdint>
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>

#include "fuzz_files.h"
#include "lucent/core/memory.h"
#include "lucent/scene/loader.h"

namespace {

namespace fs = std::filesystem;
using lucent::fuzz::scratchDirectory;
using lucent::fuzz::writeFile;

constexpr const char* kTextFiles[] = {"scene.json", "mesh.obj", "mesh.mtl"};
constexpr const char* kImageFiles[] = {"texture.png", "sky.hdr"};

}  // namespace

// The loader checks large allocations (an image's pixels) against the memory limit, as a render
// does against its --memory-limit: 1 GiB beside what the fuzzer holds at its start (-malloc_limit_mb
// is 1 GiB), so that a header that claims more is refused with a SceneError before anything is
// allocated.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  lucent::setMemoryLimit(lucent::memoryInUse() + (uint64_t(1) << 30));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  const fs::path& dir = scratchDirectory();
  size_t start = 0;
  for (const char* name : kTextFiles) {
    const size_t end = std::min(input.find('\0', start), input.size());
    if (start > input.size()) {
      std::error_code ec;
      fs::remove(dir / name, ec);
    } else {
      writeFile(dir / name, input.substr(start, end - start));
    }
    start = end + 1;
  }
  for (const char* name : kImageFiles) {
    if (start > input.size()) {
      std::error_code ec;
      fs::remove(dir / name, ec);
    } else {
      writeFile(dir / name, input.substr(start));
    }
  }
  try {
    lucent::loadScene((dir / kTextFiles[0]).string(), lucent::LoadOptions(true));
  } catch (const lucent::SceneError&) {
  }
  return 0;
}
