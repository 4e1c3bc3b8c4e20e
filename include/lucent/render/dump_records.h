// The fields of every dump record type of docs/dump-format.md, by type name: what check-dump
// compares field by field and the Python module turns into NumPy dtypes. tests/pipeline/
// test_dump_compare.cpp checks every field's offset against the C++ struct's.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace lucent {

enum class DumpFieldKind { F32, F16, U32, I32, U16, U64 };
uint32_t dumpFieldBytes(DumpFieldKind kind);

struct DumpField {
  const char* name;
  DumpFieldKind kind;
  uint32_t count;        // elements: 3 for a position, 1 for a scalar
  uint32_t columns = 0;  // a table of count / columns rows (per cache texel an RGB triple), 0: a vector
  int32_t at = -1;       // its byte offset where it shares bytes with others (a union's members); -1: after the previous field
};

struct DumpRecordType {
  uint32_t bytes;
  std::vector<DumpField> fields;  // in order, without padding; a union's members one after another, each kind's from `at`
  bool exact;                     // compared bit for bit: integers, and the grids whose floats decide cells
};

const std::map<std::string, DumpRecordType>& dumpRecordTypes();

// The byte offset of each of a record type's fields, in order.
std::vector<uint32_t> dumpFieldOffsets(const DumpRecordType& type);
// The byte offset of a record type's field (throws std::logic_error for a field it does not have).
uint32_t dumpFieldOffset(const std::string& type, const std::string& field);

}  // namespace lucent
