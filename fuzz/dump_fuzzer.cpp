// libFuzzer target for the dump reader and lucent check-dump (lucent/core/dump.h,
// lucent/render/dump_compare.h): one input is up to six dump files separated by the line
// "--file--", written in turn into a reference and a candidate directory under the names that the
// comparison's rules know (a plain array, the neighbour sets and their offsets, a tree); the two
// directories are then compared, reported and summarised as `lucent check-dump` does, with the
// tolerances taken from the input's first bytes, and each file read on its own. Every rejection must
// be a std::runtime_error or std::invalid_argument (MemoryLimitError among them); anything else, a
// crash, a sanitizer report, a hang (-timeout) or a large allocation (-malloc_limit_mb) is a defect.
// Seeds: scripts/fuzz-corpus.py dump.
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include "fuzz_files.h"
#include "lucent/core/dump.h"
#include "lucent/core/memory.h"
#include "lucent/render/dump_compare.h"

namespace {

constexpr std::array<const char*, 3> kNames = {"a.bin", "band0.global.neighbours.bin",
                                               "band0.global.neighbour_offsets.bin"};

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  lucent::setMemoryLimit(lucent::memoryInUse() + (uint64_t(1) << 30));
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view input(reinterpret_cast<const char*>(data), size);
  // The tolerances: a relative difference and a count of ulps, as check-dump takes them.
  lucent::DumpCompareOptions options;
  if (input.size() >= 8) {
    float relative;
    std::memcpy(&relative, input.data(), 4);
    std::memcpy(&options.ulps, input.data() + 4, 4);
    options.relative = relative;
    options.reported = uint32_t(options.ulps % 8);
    input.remove_prefix(8);
  }
  const std::filesystem::path& scratch = lucent::fuzz::scratchDirectory();
  const std::filesystem::path reference = scratch / "reference", candidate = scratch / "candidate";
  std::error_code ec;
  std::filesystem::remove_all(reference, ec);
  std::filesystem::remove_all(candidate, ec);
  std::filesystem::create_directories(reference);
  std::filesystem::create_directories(candidate);
  constexpr std::string_view kSeparator = "\n--file--\n";
  for (size_t file = 0; file < 2 * kNames.size() && !input.empty(); ++file) {
    const size_t end = std::min(input.find(kSeparator), input.size());
    const std::filesystem::path path = (file % 2 == 0 ? reference : candidate) / kNames[file / 2];
    lucent::fuzz::writeFile(path, input.substr(0, end));
    try {
      const lucent::DumpHeader header = lucent::readDumpHeader(path.string());
      std::string records;
      lucent::readDumpRecords(path.string(), lucent::recordTypeName(header), header.recordBytes, [&](uint64_t count) {
        records.resize(size_t(count) * header.recordBytes);
        return records.data();
      });
    } catch (const std::runtime_error&) {
    }
    input.remove_prefix(std::min(input.size(), end + kSeparator.size()));
  }
  try {
    lucent::checkDumpCompareOptions(options);
    const lucent::DumpComparison c = lucent::compareDumpDirectories(reference.string(), candidate.string(), options);
    (void)lucent::dumpComparisonJson(c);
    (void)lucent::dumpComparisonReport(c);
  } catch (const std::runtime_error&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
