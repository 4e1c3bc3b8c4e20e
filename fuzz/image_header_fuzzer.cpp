// libFuzzer target for the images lucent compare and report read: two images from one input (a
// byte choosing each one's extension, two bytes giving the first one's length, then both), whose
// headers are read and compared before their pixels, as compare does, then read and compared.
// Every rejection must be a std::invalid_argument or std::runtime_error naming a file or the
// mismatch; anything else, a crash, a sanitizer report, a hang over 10 s or an allocation over
// 1 GiB (a header claiming more than its file holds, OpenEXR's attributes among them) is a defect.
// Seeds: scripts/fuzz-corpus.py image_header.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "fuzz_files.h"
#include "lucent/core/memory.h"
#include "lucent/image/metrics.h"

namespace {
// The formats Lucent reads (and one it refuses by its name).
constexpr const char* kExtensions[] = {".exr", ".png", ".hdr", ".jpg", ".tif", ".jpeg", ".pfm", ".tga"};
}

// 16 MiB beside what the fuzzer holds: an image that would need more is refused with a
// MemoryLimitError before its pixels are allocated (decoding such images under the sanitizers would
// take seconds each, and find nothing that a smaller image would not).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  lucent::setMemoryLimit(lucent::memoryInUse() + (uint64_t(16) << 20));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  const auto dir = lucent::fuzz::scratchDirectory();
  const auto image = dir / (std::string("image") + kExtensions[data[0] % 8]);
  const auto reference = dir / (std::string("reference") + kExtensions[(data[0] / 8) % 8]);
  const size_t first = std::min<size_t>(size - 3, size_t(data[1]) | size_t(data[2]) << 8);
  const std::string_view rest(reinterpret_cast<const char*>(data) + 3, size - 3);
  lucent::fuzz::writeFile(image, rest.substr(0, first));
  lucent::fuzz::writeFile(reference, rest.substr(first));
  try {
    const lucent::ImageHeader a = lucent::readImageHeader(image.string()), b = lucent::readImageHeader(reference.string());
    lucent::checkComparable(a, b, false);
    const lucent::Image candidate = lucent::readLinearImage(image.string());
    const lucent::Image ref = lucent::readLinearImage(reference.string());
    (void)lucent::compareImages(candidate, ref);
  } catch (const std::invalid_argument&) {
  } catch (const std::runtime_error&) {
  }
  return 0;
}
