#include "lucent/core/memory.h"

#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace lucent {

namespace {

std::atomic<uint64_t> limitBytes{0};

// A number read from a file of one number ("max" or a missing file: none).
bool readNumber(const std::string& path, uint64_t& out) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text)) return false;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && ptr == text.data() + text.size();
}

// The memory the process's control group may still take: cgroup v2 (memory.max less
// memory.current), else v1 (memory.limit_in_bytes less memory.usage_in_bytes), at the group's path
// or, inside a container's namespace, at the mount's root.
uint64_t cgroupHeadroom() {
  std::ifstream cgroups("/proc/self/cgroup");
  std::string v2Path, v1Path;
  for (std::string line; std::getline(cgroups, line);) {
    const size_t a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1), path = line.substr(b + 1);
    if (line.compare(0, a, "0") == 0 && controllers.empty()) v2Path = path;
    std::istringstream list(controllers);
    for (std::string c; std::getline(list, c, ',');)
      if (c == "memory") v1Path = path;
  }
  uint64_t headroom = UINT64_MAX;
  auto consider = [&](const std::string& dir, const char* limitFile, const char* usageFile) {
    uint64_t limit = 0, usage = 0;
    if (!readNumber(dir + "/" + limitFile, limit) || !readNumber(dir + "/" + usageFile, usage)) return false;
    headroom = std::min(headroom, limit > usage ? limit - usage : 0);
    return true;
  };
  if (!v1Path.empty() && !consider("/sys/fs/cgroup/memory" + v1Path, "memory.limit_in_bytes", "memory.usage_in_bytes"))
    consider("/sys/fs/cgroup/memory", "memory.limit_in_bytes", "memory.usage_in_bytes");
  if (!v2Path.empty() && !consider("/sys/fs/cgroup" + v2Path, "memory.max", "memory.current"))
    consider("/sys/fs/cgroup", "memory.max", "memory.current");
  return headroom;
}

uint64_t residentMemory() {
  std::ifstream statm("/proc/self/statm");
  uint64_t size = 0, resident = 0;
  if (!(statm >> size >> resident)) return 0;
  return resident * uint64_t(sysconf(_SC_PAGESIZE));
}

uint64_t virtualMemory() {
  std::ifstream statm("/proc/self/statm");
  uint64_t size = 0;
  if (!(statm >> size)) return 0;
  return size * uint64_t(sysconf(_SC_PAGESIZE));
}

}  // namespace

uint64_t availableMemory() {
  uint64_t available = UINT64_MAX;
  std::ifstream meminfo("/proc/meminfo");
  for (std::string key; meminfo >> key;) {
    uint64_t kib = 0;
    meminfo >> kib;
    if (key == "MemAvailable:") available = kib * 1024;
    meminfo.ignore(1 << 10, '\n');
  }
  available = std::min(available, cgroupHeadroom());
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) {
    const uint64_t used = virtualMemory();
    available = std::min<uint64_t>(available, as.rlim_cur > used ? as.rlim_cur - used : 0);
  }
  return available;
}

uint64_t addressSpaceLimit() {
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) != 0 || as.rlim_cur == RLIM_INFINITY) return UINT64_MAX;
  return uint64_t(as.rlim_cur);
}

uint64_t memoryInUse() {
  const uint64_t resident = residentMemory();
  const uint64_t retained = mallinfo2().fordblks;
  return resident > retained ? resident - retained : 0;
}

void setMemoryLimit(uint64_t bytes) { limitBytes = bytes; }

uint64_t memoryLimit() {
  uint64_t limit = limitBytes;
  if (limit == 0) {
    const uint64_t available = availableMemory();
    limit = available == UINT64_MAX ? UINT64_MAX : memoryInUse() + available;
    uint64_t unset = 0;
    if (!limitBytes.compare_exchange_strong(unset, limit)) limit = unset;
  }
  return limit;
}

void requireMemory(uint64_t bytes, std::string_view what, std::string_view remedy) {
  const uint64_t limit = memoryLimit(), inUse = memoryInUse();
  if (bytes <= limit && inUse <= limit - bytes) return;
  throw MemoryLimitError(std::string(what) + " would need " + memoryText(bytes) + " beside the " + memoryText(inUse) +
                         " in use, beyond the memory limit of " + memoryText(limit) +
                         " (--memory-limit; default: the available memory): " + std::string(remedy));
}

std::string memoryText(uint64_t bytes) {
  static const char* const units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double value = double(bytes);
  int unit = 0;
  while (value >= 1024 && unit < 6) value /= 1024, ++unit;
  std::ostringstream s;
  if (unit == 0) s << bytes << " bytes";
  else s << std::fixed << std::setprecision(value < 10 ? 2 : value < 100 ? 1 : 0) << value << " " << units[unit];
  return s.str();
}

uint64_t parseMemorySize(std::string_view text) {
  const std::string original(text);
  auto fail = [&] {
    return std::invalid_argument("'" + original + "': expected a size such as 512M, 1.5G or 8GiB (bytes without a suffix)");
  };
  double number = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), number);
  if (ec != std::errc() || !(number >= 0) || !std::isfinite(number)) throw fail();
  std::string_view suffix(ptr, size_t(text.data() + text.size() - ptr));
  double scale = 1;
  if (!suffix.empty()) {
    const size_t power = std::string_view("KMGT").find(char(std::toupper(suffix[0])));
    if (power == std::string_view::npos) throw fail();
    scale = std::ldexp(1.0, 10 * int(power + 1));
    suffix.remove_prefix(1);
    if (suffix != "" && suffix != "B" && suffix != "iB") throw fail();
  }
  const double bytes = std::round(number * scale);
  if (bytes >= 0x1p64) throw fail();
  return uint64_t(bytes);
}

}  // namespace lucent
