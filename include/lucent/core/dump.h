// Binary dumps of a stage's flat arrays, so that another backend (a GPU port of a method) can be
// checked against Lucent stage by stage: one file per array, a 64-byte header and then the records
// exactly as they lie in memory (little-endian). docs/dump-format.md gives the header and the
// fields of every record type.
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace lucent {

struct DumpHeader {
  char magic[8];          // "LCNTDUMP"
  uint32_t version;       // kDumpVersion
  uint32_t recordBytes;   // size of one record
  uint64_t count;         // records that follow the header
  char type[40];          // the record type's name, NUL-padded ASCII ("Photon", "uint32", ...)
};
static_assert(sizeof(DumpHeader) == 64 && std::is_trivially_copyable_v<DumpHeader>);

inline constexpr uint32_t kDumpVersion = 1;

// Writes <directory>/<name>.bin whole or not at all (a temporary file, then a rename); throws
// std::runtime_error naming the file when it cannot.
void writeDump(const std::string& directory, const std::string& name, const std::string& type,
               const void* records, uint32_t recordBytes, uint64_t count);

template <class T, size_t Extent>
void writeDump(const std::string& directory, const std::string& name, const std::string& type,
               std::span<T, Extent> records) {
  static_assert(std::is_trivially_copyable_v<T>, "dumps hold plain records");
  writeDump(directory, name, type, records.data(), uint32_t(sizeof(T)), records.size());
}

// Whether `offsets` cut `total` entries into runs (a CSR array's offsets: run i is entries
// [offsets[i], offsets[i + 1])): non-decreasing from 0 to total. Dumps are input; whoever follows
// dumped offsets checks them first.
template <class Offset>
bool offsetsCutRuns(const std::vector<Offset>& offsets, uint64_t total) {
  bool ok = !offsets.empty() && offsets.front() == 0 && uint64_t(offsets.back()) == total;
  for (size_t i = 1; ok && i < offsets.size(); ++i) ok = offsets[i - 1] <= offsets[i];
  return ok;
}

// Why `directory` cannot take dumps, or "" if it can (or is "": no dumps): it is a directory, or
// missing with a directory as its nearest existing ancestor (writeDump creates it and its missing
// parents with the first file).
std::string dumpDirectoryProblem(const std::string& directory);

// Creates `directory` and its missing parents (writeDump's, and the settings file's); throws
// std::runtime_error naming it when it cannot.
void createDumpDirectory(const std::string& directory);

// The header's record type name (its type field up to the first NUL).
std::string recordTypeName(const DumpHeader& header);

// The header of a dump file; throws std::runtime_error naming the file if it is not one (its type
// name, too, must be letters, digits and _).
DumpHeader readDumpHeader(const std::string& path);

// The records of a dump file, checked against the expected type name and record size, the
// header's count against the file's length and the records against the memory limit
// (core/memory.h: MemoryLimitError), then read into storage(count); throws std::runtime_error
// naming the file otherwise. The file is opened once; it must be a regular file.
void readDumpRecords(const std::string& path, const std::string& type, uint32_t recordBytes,
                     const std::function<void*(uint64_t count)>& storage);
template <class T>
std::vector<T> readDump(const std::string& path, const std::string& type) {
  static_assert(std::is_trivially_copyable_v<T>, "dumps hold plain records");
  std::vector<T> records;
  readDumpRecords(path, type, uint32_t(sizeof(T)), [&](uint64_t count) {
    records.resize(count);
    return static_cast<void*>(records.data());
  });
  return records;
}

}  // namespace lucent
