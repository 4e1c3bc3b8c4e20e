#include "lucent/core/dump.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "lucent/core/files.h"
#include "lucent/core/memory.h"
#include "lucent/core/text.h"

namespace lucent {

// Records are written as they lie in memory, and the format is little-endian.
static_assert(std::endian::native == std::endian::little);

namespace {
constexpr char kDumpMagic[8] = {'L', 'C', 'N', 'T', 'D', 'U', 'M', 'P'};
}

void writeDump(const std::string& directory, const std::string& name, const std::string& type,
               const void* records, uint32_t recordBytes, uint64_t count) {
  const std::filesystem::path path = std::filesystem::path(directory) / (name + ".bin");
  if (type.size() >= sizeof(DumpHeader::type)) throw std::logic_error("dump type name too long: " + type);
  createDumpDirectory(directory);
  DumpHeader header{};
  std::memcpy(header.magic, kDumpMagic, sizeof kDumpMagic);
  header.version = kDumpVersion;
  header.recordBytes = recordBytes;
  header.count = count;
  std::memcpy(header.type, type.data(), type.size());
  writeFileAtomically(path, "dump", [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw WriteFailure("cannot create it (is '" + directory + "' a writable directory?)");
    out.write(reinterpret_cast<const char*>(&header), sizeof header);
    out.write(static_cast<const char*>(records), std::streamsize(uint64_t(recordBytes) * count));
    out.close();
    if (!out) throw WriteFailure("write failed");
  });
}

void createDumpDirectory(const std::string& directory) {
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  if (ec) throw std::runtime_error("cannot create dump directory '" + directory + "': " + ec.message());
}

std::string dumpDirectoryProblem(const std::string& directory) {
  if (directory.empty()) return "";
  std::error_code ec;
  std::filesystem::path at = std::filesystem::absolute(directory, ec);
  if (ec) return "dump directory '" + directory + "': " + ec.message();
  // The nearest part of the path that exists must be a directory: a file there would block it.
  for (; !at.empty(); at = at.parent_path()) {
    const std::filesystem::file_status status = std::filesystem::status(at, ec);
    if (std::filesystem::exists(status)) {
      if (std::filesystem::is_directory(status)) return "";
      return "dump directory '" + directory + "': '" + at.string() + "' is not a directory";
    }
    if (at == at.parent_path()) break;
  }
  return "dump directory '" + directory + "' cannot be created";
}

namespace {
// The dump file opened for reading: a regular file (a FIFO would block for ever).
std::ifstream openDump(const std::string& path) {
  const std::string problem = regularFileProblem(path);
  if (!problem.empty()) throw std::runtime_error("cannot read dump '" + path + "': " + problem);
  return std::ifstream(path, std::ios::binary);
}

DumpHeader readHeader(std::ifstream& in, const std::string& path) {
  if (!in) throw std::runtime_error("cannot read dump '" + path + "'");
  DumpHeader header{};
  in.read(reinterpret_cast<char*>(&header), sizeof header);
  if (!in || std::memcmp(header.magic, kDumpMagic, sizeof kDumpMagic) != 0)
    throw std::runtime_error("'" + path + "' is not a Lucent dump");
  if (header.version != kDumpVersion)
    throw std::runtime_error("dump '" + path + "' has format version " + std::to_string(header.version) +
                             "; this Lucent reads version " + std::to_string(kDumpVersion));
  // A type name is an identifier: anything else in the field (a terminal's escape sequences) is
  // never printed as it is.
  const std::string type = recordTypeName(header);
  const bool identifier = !type.empty() && std::all_of(type.begin(), type.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
  if (!identifier)
    throw std::runtime_error("dump '" + path + "' has a record type name that is not ASCII letters, digits and _: '" +
                             excerpt(std::string_view(header.type, sizeof header.type), 48) + "'");
  return header;
}
}  // namespace

std::string recordTypeName(const DumpHeader& header) {
  return std::string(header.type, strnlen(header.type, sizeof header.type));
}

DumpHeader readDumpHeader(const std::string& path) {
  std::ifstream in = openDump(path);
  return readHeader(in, path);
}

void readDumpRecords(const std::string& path, const std::string& type, uint32_t recordBytes,
                     const std::function<void*(uint64_t count)>& storage) {
  std::ifstream in = openDump(path);
  const DumpHeader header = readHeader(in, path);
  const std::string stored = recordTypeName(header);
  if (recordBytes == 0 || header.recordBytes == 0)
    throw std::runtime_error("dump '" + path + "' announces records of 0 bytes");
  if (stored != type || header.recordBytes != recordBytes)
    throw std::runtime_error("dump '" + path + "' holds " + stored + " records of " +
                             std::to_string(header.recordBytes) + " bytes, not " + type + " of " +
                             std::to_string(recordBytes));
  // The length is checked before anything is allocated: a damaged count must not ask for terabytes.
  in.seekg(0, std::ios::end);
  const uint64_t payload = uint64_t(in.tellg()) - sizeof(DumpHeader);
  if (!in || header.count > payload / recordBytes)
    throw std::runtime_error("dump '" + path + "' is truncated: " + std::to_string(header.count) + " records of " +
                             std::to_string(recordBytes) + " bytes announced, " + std::to_string(payload) +
                             " bytes present");
  // Bytes after the records mean the count or the record size is not what the writer meant.
  if (payload != header.count * recordBytes)
    throw std::runtime_error("dump '" + path + "' has " + std::to_string(payload - header.count * recordBytes) +
                             " bytes after its " + std::to_string(header.count) + " records of " +
                             std::to_string(recordBytes) + " bytes");
  // A sparse file can claim more than the machine holds.
  requireMemory(header.count * recordBytes, "dump '" + path + "'", "read a smaller dump");
  void* records = storage(header.count);
  in.seekg(sizeof(DumpHeader));
  in.read(static_cast<char*>(records), std::streamsize(uint64_t(recordBytes) * header.count));
  if (!in) throw std::runtime_error("dump '" + path + "' could not be read");
}

}  // namespace lucent
