// Compares another backend's stage dumps with Lucent's, array by array, by each record type's rules
// (docs/dump-format.md, "Comparing dumps"): photons as multisets, kNN results as sets allowing for
// ties at the radius, the environment paper's node tree by its structure, integers (grids, sorted
// and index arrays) exactly, floating-point fields within a relative or ulp tolerance.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace lucent {

struct DumpCompareOptions {
  double relative = 1e-5;  // two floats agree within this relative difference,
  uint32_t ulps = 4;       // or this many units in the last place (binary16 ulps for HalfRgb)
  size_t reported = 5;     // differences reported per array
};

// One differing record: its index (for multisets, the index in the reference after sorting; for
// trees, the reference's node), what it stands for where the reference's directory tells (a
// shading point's pixel, sample and branch; a photon grid's cell), the first field that differs
// and both values as text.
struct RecordDifference {
  uint64_t index = 0;
  std::string where;
  std::string field, reference, candidate;
};

struct ArrayComparison {
  std::string name, type;  // the file name without ".bin", the record type
  std::string rule;        // "exact", "elementwise", "multiset", "neighbour sets", "tree"
  uint64_t referenceRecords = 0, candidateRecords = 0, differing = 0;
  std::vector<RecordDifference> first;
  std::string problem;  // why the arrays could not be compared record by record ("" if they were)
  bool passed() const { return problem.empty() && differing == 0; }
};

struct DumpComparison {
  std::vector<ArrayComparison> arrays;                      // the arrays both directories hold
  std::vector<std::string> onlyInReference, onlyInCandidate;  // not compared
  bool passed() const;
};

// Throws std::invalid_argument naming the option (as the command line spells it) for a tolerance or
// count out of range (NaN included).
void checkDumpCompareOptions(const DumpCompareOptions& options);

// Every dump file (*.bin) both directories hold, compared; throws std::runtime_error naming the
// directory or file when a directory cannot be read or a file is not a dump (a FIFO or device
// named *.bin included), and std::invalid_argument as checkDumpCompareOptions.
DumpComparison compareDumpDirectories(const std::string& reference, const std::string& candidate,
                                      const DumpCompareOptions& options = {});

// The comparison as one line of JSON: passed, each array's name, type, rule, records, differing
// count, problem and first differing records, and the arrays only one side holds.
std::string dumpComparisonJson(const DumpComparison& comparison);
// A line per array that differs, each followed by its first differing records.
std::string dumpComparisonReport(const DumpComparison& comparison);

}  // namespace lucent
