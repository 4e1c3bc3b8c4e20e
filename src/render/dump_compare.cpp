#include "lucent/render/dump_compare.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/json_text.h"
#include "lucent/core/dump.h"
#include "lucent/render/dump_records.h"

namespace lucent {

bool DumpComparison::passed() const {
  return !arrays.empty() && std::all_of(arrays.begin(), arrays.end(), [](const ArrayComparison& a) { return a.passed(); });
}

namespace {

struct Array {
  std::string type;
  uint32_t recordBytes = 0;
  uint64_t count = 0;
  std::vector<std::byte> bytes;
  const std::byte* record(uint64_t i) const { return bytes.data() + i * recordBytes; }
};

Array readArray(const std::filesystem::path& path) {
  Array a;
  const DumpHeader h = readDumpHeader(path.string());
  a.type = recordTypeName(h);
  a.recordBytes = h.recordBytes;
  readDumpRecords(path.string(), a.type, a.recordBytes, [&](uint64_t count) {
    a.count = count;
    a.bytes.resize(count * a.recordBytes);
    return static_cast<void*>(a.bytes.data());
  });
  return a;
}

template <class T>
T loadAs(const std::byte* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// Floats on a line of integers: adjacent floats differ by one.
int64_t ordered(uint32_t bits) { return (bits & 0x80000000u) ? -int64_t(bits & 0x7fffffffu) : int64_t(bits); }
int64_t ordered16(uint16_t bits) { return (bits & 0x8000u) ? -int64_t(bits & 0x7fffu) : int64_t(bits); }

bool floatsAgree(float a, float b, const DumpCompareOptions& o) {
  if (std::bit_cast<uint32_t>(a) == std::bit_cast<uint32_t>(b) || (std::isnan(a) && std::isnan(b))) return true;
  if (std::isnan(a) || std::isnan(b) || std::isinf(a) || std::isinf(b)) return false;  // an infinity only equals itself
  if (std::abs(double(a) - double(b)) <= o.relative * std::max(std::abs(double(a)), std::abs(double(b)))) return true;
  return std::abs(ordered(std::bit_cast<uint32_t>(a)) - ordered(std::bit_cast<uint32_t>(b))) <= int64_t(o.ulps);
}

std::string valueText(DumpFieldKind k, const std::byte* p) {
  std::ostringstream s;
  s.precision(9);
  switch (k) {
    case DumpFieldKind::F32: s << loadAs<float>(p); break;
    case DumpFieldKind::F16: s << "0x" << std::hex << loadAs<uint16_t>(p) << " (binary16)"; break;
    case DumpFieldKind::U32: s << loadAs<uint32_t>(p); break;
    case DumpFieldKind::I32: s << loadAs<int32_t>(p); break;
    case DumpFieldKind::U16: s << loadAs<uint16_t>(p); break;
    case DumpFieldKind::U64: s << loadAs<uint64_t>(p); break;
  }
  return s.str();
}

// The first field of two records that differs, or false; `skip` names fields not compared.
bool firstDifference(const DumpRecordType* type, uint32_t recordBytes, const std::byte* a, const std::byte* b,
                     const DumpCompareOptions& o, RecordDifference& d, const std::set<std::string>& skip = {}) {
  if (!type) {  // a type this Lucent does not know: bytes
    if (std::memcmp(a, b, recordBytes) == 0) return false;
    d.field = "bytes";
    d.reference = d.candidate = "(differ)";
    return true;
  }
  const std::vector<uint32_t> offsets = dumpFieldOffsets(*type);
  for (size_t field = 0; field < type->fields.size(); ++field) {
    const DumpField& f = type->fields[field];
    const uint32_t size = dumpFieldBytes(f.kind);
    uint32_t offset = offsets[field];
    for (uint32_t i = 0; i < f.count; ++i, offset += size) {
      if (skip.count(f.name)) continue;
      const std::byte *x = a + offset, *y = b + offset;
      bool same = std::memcmp(x, y, size) == 0;
      if (!same && !type->exact) {
        if (f.kind == DumpFieldKind::F32) same = floatsAgree(loadAs<float>(x), loadAs<float>(y), o);
        if (f.kind == DumpFieldKind::F16) {
          const uint16_t hx = loadAs<uint16_t>(x), hy = loadAs<uint16_t>(y);
          const bool special = (hx & 0x7c00u) == 0x7c00u || (hy & 0x7c00u) == 0x7c00u;  // infinities and NaNs
          same = !special && std::abs(ordered16(hx) - ordered16(hy)) <= int64_t(o.ulps);
        }
      }
      if (!same) {
        d.field = f.count > 1 ? std::string(f.name) + "[" + std::to_string(i) + "]" : std::string(f.name);
        d.reference = valueText(f.kind, x);
        d.candidate = valueText(f.kind, y);
        return true;
      }
    }
  }
  return false;
}

void note(ArrayComparison& c, const DumpCompareOptions& o, RecordDifference d) {
  ++c.differing;
  if (c.first.size() < o.reported) c.first.push_back(std::move(d));
}

void compareElementwise(const Array& r, const Array& c, const DumpRecordType* type, const DumpCompareOptions& o,
                        ArrayComparison& out, const std::vector<uint64_t>* order = nullptr,
                        const std::vector<uint64_t>* candidateOrder = nullptr) {
  for (uint64_t i = 0; i < r.count; ++i) {
    const uint64_t ri = order ? (*order)[i] : i, ci = candidateOrder ? (*candidateOrder)[i] : i;
    RecordDifference d;
    if (firstDifference(type, r.recordBytes, r.record(ri), c.record(ci), o, d)) {
      d.index = i;
      if (order) d.field += " (reference record " + std::to_string(ri) + ", candidate record " + std::to_string(ci) + ")";
      note(out, o, std::move(d));
    }
  }
}

// Photons in any order: both sorted by position, then by every byte.
std::vector<uint64_t> photonOrder(const Array& a) {
  std::vector<uint64_t> order(a.count);
  std::iota(order.begin(), order.end(), uint64_t(0));
  std::sort(order.begin(), order.end(), [&](uint64_t i, uint64_t j) {
    for (int k = 0; k < 3; ++k) {  // by the floats' bits on the ordered line: a strict order even with NaNs
      const int64_t x = ordered(loadAs<uint32_t>(a.record(i) + 4 * k)), y = ordered(loadAs<uint32_t>(a.record(j) + 4 * k));
      if (x != y) return x < y;
    }
    return std::memcmp(a.record(i), a.record(j), a.recordBytes) < 0;
  });
  return order;
}

struct Neighbour {  // a PhotonDistance record
  float d2;
  uint32_t photon;
};

// Per query the photons of the reference's search and the candidate's: those strictly inside the
// reference's farthest distance must be the same photons at the same distances; the candidate's
// others must lie at that distance (ties: an exact-k search may keep other photons of a tie, or
// fewer of them) and be among the reference's tied ones, at least one of them where there are any.
void compareNeighbours(const Array& r, const Array& c, const std::vector<uint64_t>& ro, const std::vector<uint64_t>& co,
                       const DumpCompareOptions& o, ArrayComparison& out) {
  const uint64_t queries = ro.size() - 1;
  for (uint64_t q = 0; q < queries; ++q) {
    auto entries = [](const Array& a, uint64_t begin, uint64_t end) {
      std::vector<Neighbour> v;
      for (uint64_t i = begin; i < end && i < a.count; ++i) v.push_back(loadAs<Neighbour>(a.record(i)));
      std::sort(v.begin(), v.end(), [](Neighbour x, Neighbour y) {
        const int64_t dx = ordered(std::bit_cast<uint32_t>(x.d2)), dy = ordered(std::bit_cast<uint32_t>(y.d2));
        return dx != dy ? dx < dy : x.photon < y.photon;
      });
      return v;
    };
    const std::vector<Neighbour> R = entries(r, ro[q], ro[q + 1]), C = entries(c, co[q], co[q + 1]);
    bool same = R.empty() == C.empty();
    if (same && !R.empty()) {
      const float farthest = R.back().d2;
      std::map<uint32_t, float> inside;
      std::set<uint32_t> tied;
      for (const Neighbour& n : R) {
        if (floatsAgree(n.d2, farthest, o)) tied.insert(n.photon);
        else inside[n.photon] = n.d2;
      }
      const bool hadTied = !tied.empty();
      size_t tiedMatched = 0;
      for (const Neighbour& n : C) {  // each photon matched once: a repeated one is not matched again
        const auto at = inside.find(n.photon);
        if (at != inside.end() && floatsAgree(at->second, n.d2, o)) inside.erase(at);
        else if (tied.erase(n.photon) && floatsAgree(n.d2, farthest, o)) ++tiedMatched;
        else same = false;
      }
      same &= inside.empty() && (!hadTied || tiedMatched > 0);
    }
    if (!same) {
      RecordDifference d;
      d.index = q;
      d.field = "neighbour set";
      auto text = [](const std::vector<Neighbour>& v) {
        std::ostringstream s;
        s.precision(9);
        s << v.size() << " photons";
        if (!v.empty()) s << ", farthest d2 " << v.back().d2;
        return s.str();
      };
      d.reference = text(R), d.candidate = text(C);
      note(out, o, std::move(d));
    }
  }
}

// The environment paper's tree, walked from the root in both: the same shape, the same nodes (within
// the tolerance) and the same selection bits at every place in it, whatever the nodes' numbering.
void compareTrees(const Array& r, const Array& c, const DumpRecordType* type, const DumpCompareOptions& o, ArrayComparison& out) {
  const uint32_t root = 1;
  if (r.count <= root || c.count <= root) {
    if (r.count != c.count) out.problem = "one of the trees is empty";
    return;
  }
  std::vector<std::pair<uint32_t, uint32_t>> stack = {{root, root}};
  std::vector<bool> seenA(r.count), seenB(c.count);
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    if (a >= r.count || b >= c.count) {
      out.problem = "a child index beyond the array";
      return;
    }
    if (seenA[a] || seenB[b]) {  // a cycle, or a node with two parents
      out.problem = "not a tree: a node is reached twice";
      return;
    }
    seenA[a] = seenB[b] = true;
    RecordDifference d;
    d.index = a;
    static const uint32_t child = dumpFieldOffset("EnvPointNode", "child");
    const uint32_t ca0 = loadAs<uint32_t>(r.record(a) + child), ca1 = loadAs<uint32_t>(r.record(a) + child + 4);
    const uint32_t cb0 = loadAs<uint32_t>(c.record(b) + child), cb1 = loadAs<uint32_t>(c.record(b) + child + 4);
    const bool leafA = ca0 == 0, leafB = cb0 == 0;
    if (leafA != leafB) {
      d.field = "child";
      d.reference = leafA ? "leaf" : "interior", d.candidate = leafB ? "leaf" : "interior";
      note(out, o, std::move(d));
      continue;
    }
    if (firstDifference(type, r.recordBytes, r.record(a), c.record(b), o, d, {"child", "skip"})) note(out, o, std::move(d));
    if (!leafA) {
      stack.push_back({ca1, cb1});
      stack.push_back({ca0, cb0});
    }
  }
}

std::vector<uint64_t> offsetsOf(const Array& a) {
  std::vector<uint64_t> v(a.count);
  std::memcpy(v.data(), a.bytes.data(), a.bytes.size());
  return v;
}

bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// What a record index of an array stands for, from the reference's directory: per shading point
// (the arrays beside a band's or the image's shading_points, and a search's queries), its pixel
// (x, y with settings.json's width), sample and branch; per cell of a photon map's grid, the cell.
class RecordPlaces {
 public:
  explicit RecordPlaces(std::filesystem::path directory) : directory_(std::move(directory)) {
    if (!std::filesystem::is_regular_file(directory_ / "settings.json")) return;
    std::ifstream in(directory_ / "settings.json");
    if (!in) return;
    const nlohmann::json settings = nlohmann::json::parse(in, nullptr, false);
    if (settings.is_object() && settings.contains("width") && settings["width"].is_number_unsigned())
      width_ = settings["width"].get<uint64_t>();
  }

  std::string of(const std::string& array, uint64_t index) {
    const size_t dot = array.rfind('.');
    const std::string last = dot == std::string::npos ? array : array.substr(dot + 1);
    static const std::set<std::string> perPoint = {"shading_points", "direct", "indirect", "caustic", "receiver_tiles", "neighbours"};
    if (perPoint.count(last)) {
      // band<N>.direct and band<N>.<map>.neighbours beside band<N>.shading_points; direct beside shading_points.
      const size_t first = array.find('.');
      const std::string prefix = array.rfind("band", 0) == 0 && first != std::string::npos ? array.substr(0, first + 1) : "";
      const Array* points = referenceArray(prefix + "shading_points", "ShadingPoint");
      if (!points || index >= points->count) return "";
      const std::byte* p = points->record(index);
      const auto field = [p](const char* name) { return loadAs<uint32_t>(p + dumpFieldOffset("ShadingPoint", name)); };
      const uint32_t pixel = field("pixel"), sample = field("sample"), branch = field("branch");
      std::string at = width_ > 0 ? "pixel (" + std::to_string(pixel % width_) + ", " + std::to_string(pixel / width_) + ")"
                                  : "pixel " + std::to_string(pixel) + " (y * width + x)";
      return "shading point " + std::to_string(index) + ": " + at + ", sample " + std::to_string(sample) + ", branch " +
             std::to_string(branch);
    }
    static const std::set<std::string> perCell = {"arrived", "first_photon", "slots", "cell_counts"};
    if (perCell.count(last) && dot != std::string::npos) {
      const Array* grid = referenceArray(array.substr(0, dot) + ".grid", "UniformGrid");
      if (!grid || grid->count != 1) return "";
      int64_t res[3];
      for (int a = 0; a < 3; ++a) res[a] = loadAs<int32_t>(grid->record(0) + dumpFieldOffset("UniformGrid", "res") + 4 * a);
      if (res[0] < 1 || res[1] < 1 || res[2] < 1) return "";
      // cell_counts: the prefix sums' entries, res + 1 per axis; slots: m^2 per cell.
      const int64_t side[3] = {res[0] + (last == "cell_counts"), res[1] + (last == "cell_counts"), res[2] + (last == "cell_counts")};
      const uint64_t cells = uint64_t(side[0] * side[1] * side[2]);
      uint64_t cell = index, slot = 0;
      if (last == "slots") {
        const Array* slots = referenceArray(array, "uint32");
        const uint64_t perCellSlots = slots && slots->count % cells == 0 ? slots->count / cells : 0;
        if (perCellSlots == 0) return "";
        cell = index / perCellSlots, slot = index % perCellSlots;
      }
      if (cell >= cells) return "";
      const uint64_t x = cell % uint64_t(side[0]), y = cell / uint64_t(side[0]) % uint64_t(side[1]),
                     z = cell / uint64_t(side[0] * side[1]);
      return std::string(last == "cell_counts" ? "prefix sum below cell (" : "cell (") + std::to_string(x) + ", " +
             std::to_string(y) + ", " + std::to_string(z) + ")" + (last == "slots" ? ", slot " + std::to_string(slot) : "");
    }
    return "";
  }

 private:
  // The reference's array of that name and type, read once; null where it has none (or another type).
  const Array* referenceArray(const std::string& name, const std::string& type) {
    auto found = arrays_.find(name);
    if (found == arrays_.end()) {
      std::optional<Array> array;
      const std::filesystem::path path = directory_ / (name + ".bin");
      if (std::filesystem::is_regular_file(path)) {
        try {
          array = readArray(path);
        } catch (const std::exception&) {  // compared (and refused) as an array of its own
        }
      }
      found = arrays_.emplace(name, std::move(array)).first;
    }
    return found->second && found->second->type == type ? &*found->second : nullptr;
  }
  std::filesystem::path directory_;
  uint64_t width_ = 0;
  std::map<std::string, std::optional<Array>> arrays_;
};

}  // namespace

void checkDumpCompareOptions(const DumpCompareOptions& options) {
  // CLI11's range check lets NaN through, and reads -1 as a huge count.
  if (!(options.relative >= 0 && options.relative <= 1)) throw std::invalid_argument("--relative must lie in [0, 1]");
  if (options.ulps > (1u << 24)) throw std::invalid_argument("--ulps must lie in [0, 2^24]");
  if (options.reported > 1000000) throw std::invalid_argument("--report must lie in [0, 1000000]");
}

DumpComparison compareDumpDirectories(const std::string& reference, const std::string& candidate,
                                      const DumpCompareOptions& options) {
  namespace fs = std::filesystem;
  checkDumpCompareOptions(options);
  auto names = [](const std::string& dir) {
    if (!fs::is_directory(dir)) throw std::runtime_error("'" + dir + "' is not a directory");
    std::set<std::string> n;
    for (const auto& e : fs::directory_iterator(dir))
      if (!e.is_directory() && e.path().extension() == ".bin") n.insert(e.path().stem().string());  // a FIFO too: refused when read
    return n;
  };
  const std::set<std::string> ref = names(reference), cand = names(candidate);
  DumpComparison out;
  for (const std::string& n : ref)
    if (!cand.count(n)) out.onlyInReference.push_back(n);
  for (const std::string& n : cand)
    if (!ref.count(n)) out.onlyInCandidate.push_back(n);
  for (const std::string& name : ref) {
    if (!cand.count(name)) continue;
    // A kNN search's offsets are compared with its neighbours, as one array.
    if (endsWith(name, ".neighbour_offsets") && ref.count(name.substr(0, name.size() - 18) + ".neighbours")) continue;
    const Array r = readArray(fs::path(reference) / (name + ".bin")), c = readArray(fs::path(candidate) / (name + ".bin"));
    ArrayComparison a;
    a.name = name, a.type = r.type, a.referenceRecords = r.count, a.candidateRecords = c.count;
    const auto known = dumpRecordTypes().find(r.type);
    const DumpRecordType* type = known == dumpRecordTypes().end() ? nullptr : &known->second;
    if (c.type != r.type || c.recordBytes != r.recordBytes) {
      a.problem = "record type " + c.type + " (" + std::to_string(c.recordBytes) + " bytes) in the candidate, " + r.type +
                  " (" + std::to_string(r.recordBytes) + " bytes) in the reference";
    } else if (type && type->bytes != r.recordBytes) {
      a.problem = r.type + " records of " + std::to_string(r.recordBytes) + " bytes, not " + std::to_string(type->bytes);
    } else if (r.type == "PhotonDistance" && endsWith(name, ".neighbours")) {
      a.rule = "neighbour sets";
      const std::string offsets = name.substr(0, name.size() - 11) + ".neighbour_offsets";
      if (!ref.count(offsets) || !cand.count(offsets)) {
        a.problem = "no " + offsets + " beside it in both directories";
      } else {
        const Array rOffsets = readArray(fs::path(reference) / (offsets + ".bin"));
        const Array cOffsets = readArray(fs::path(candidate) / (offsets + ".bin"));
        const bool uint64s = rOffsets.type == "uint64" && rOffsets.recordBytes == 8 && cOffsets.type == "uint64" &&
                             cOffsets.recordBytes == 8;
        const std::vector<uint64_t> ro = uint64s ? offsetsOf(rOffsets) : std::vector<uint64_t>();
        const std::vector<uint64_t> co = uint64s ? offsetsOf(cOffsets) : std::vector<uint64_t>();
        if (!uint64s) a.problem = offsets + " is not a uint64 array";
        else if (ro.size() != co.size() || ro.empty()) a.problem = "the searches' counts differ";
        else if (!offsetsCutRuns(ro, r.count) || !offsetsCutRuns(co, c.count)) a.problem = offsets + " are not offsets from 0 to the neighbours' count";
        else compareNeighbours(r, c, ro, co, options, a);
      }
    } else if (r.count != c.count) {
      a.problem = std::to_string(r.count) + " records in the reference, " + std::to_string(c.count) + " in the candidate";
    } else if (r.type == "Photon") {
      a.rule = "multiset";
      const std::vector<uint64_t> ro = photonOrder(r), co = photonOrder(c);
      compareElementwise(r, c, type, options, a, &ro, &co);
    } else if (r.type == "EnvPointNode") {
      a.rule = "tree";
      compareTrees(r, c, type, options, a);
    } else {
      a.rule = !type || type->exact ? "exact" : "elementwise";
      compareElementwise(r, c, type, options, a);
    }
    out.arrays.push_back(std::move(a));
  }
  RecordPlaces places{fs::path(reference)};
  for (ArrayComparison& a : out.arrays)
    if (a.rule != "tree" && a.rule != "multiset")
      for (RecordDifference& d : a.first) d.where = places.of(a.name, d.index);
  return out;
}

std::string dumpComparisonJson(const DumpComparison& c) {
  nlohmann::json arrays = nlohmann::json::array();
  for (const ArrayComparison& a : c.arrays) {
    nlohmann::json j = {{"name", a.name}, {"type", a.type}, {"rule", a.rule}, {"reference_records", a.referenceRecords},
                        {"candidate_records", a.candidateRecords}, {"differing", a.differing}, {"passed", a.passed()}};
    if (!a.problem.empty()) j["problem"] = a.problem;
    nlohmann::json first = nlohmann::json::array();
    for (const RecordDifference& d : a.first)
      first.push_back({{"index", d.index}, {"where", d.where}, {"field", d.field}, {"reference", d.reference},
                       {"candidate", d.candidate}});
    if (!first.empty()) j["first_differing"] = first;
    arrays.push_back(j);
  }
  const nlohmann::json out = {{"passed", c.passed()}, {"arrays", arrays}, {"only_in_reference", c.onlyInReference},
                              {"only_in_candidate", c.onlyInCandidate}};
  return jsonText(out);
}

std::string dumpComparisonReport(const DumpComparison& c) {
  std::ostringstream s;
  for (const ArrayComparison& a : c.arrays) {
    if (a.passed()) continue;
    s << a.name << " (" << a.type << ", " << (a.rule.empty() ? "not compared" : a.rule) << "): ";
    if (a.problem.empty()) s << a.differing << " of " << a.referenceRecords << " records differ\n";
    else s << a.problem << "\n";
    for (const RecordDifference& d : a.first)
      s << "  record " << d.index << (d.where.empty() ? "" : " (" + d.where + ")") << " " << d.field << ": "
        << d.reference << " in the reference, " << d.candidate << " in the candidate\n";
  }
  return s.str();
}

}  // namespace lucent
