#include "lucent/core/files.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>

namespace lucent {

namespace {

// Who writes a temporary file: the machine's boot (the kernel's random boot id, which differs
// between machines and between boots of one), the process-id namespace (containers on one kernel
// number their processes apart) and the process id with the process's start time (ids are reused).
// A field that cannot be read is 0, and a name with a 0 field is never proven abandoned.
struct Writer {
  uint64_t boot = 0, pidNamespace = 0, pid = 0, startTicks = 0;
};

// Field 22 of /proc/PID/stat: the process's start time in clock ticks after boot; nullopt when the
// process does not exist, 0 when its state cannot be read.
std::optional<uint64_t> processStartTicks(uint64_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  if (!in) {
    struct stat s {};
    if (::stat(("/proc/" + std::to_string(pid)).c_str(), &s) != 0 && errno == ENOENT) return std::nullopt;
    return 0;
  }
  std::string line;
  std::getline(in, line);
  // The command name (field 2) is in parentheses and may hold spaces and parentheses itself.
  const size_t end = line.rfind(')');
  if (end == std::string::npos) return 0;
  std::istringstream fields(line.substr(end + 1));
  std::string field;
  for (int i = 3; i <= 22 && (fields >> field); ++i)
    if (i == 22) {
      uint64_t ticks = 0;
      const auto [p, ec] = std::from_chars(field.data(), field.data() + field.size(), ticks);
      return ec == std::errc() && p == field.data() + field.size() ? ticks : 0;
    }
  return 0;
}

// Whether /proc shows this process as itself: a /proc of another pid namespace (unshare -p without
// a new mount) would answer for other processes than the ids name.
bool procIsOurs() {
  std::ifstream in("/proc/self/stat");
  uint64_t pid = 0;
  return (in >> pid) && pid == uint64_t(::getpid());
}

Writer readThisWriter() {
  Writer w;
  std::ifstream bootId("/proc/sys/kernel/random/boot_id");
  std::string id;
  if (bootId >> id) {
    std::string hex;
    for (char c : id)
      if (std::isxdigit(static_cast<unsigned char>(c))) hex += char(std::tolower(static_cast<unsigned char>(c)));
    if (hex.size() >= 16) std::from_chars(hex.data(), hex.data() + 16, w.boot, 16);
  }
  struct stat ns {};
  if (::stat("/proc/self/ns/pid", &ns) == 0) w.pidNamespace = uint64_t(ns.st_ino);
  w.pid = uint64_t(::getpid());
  w.startTicks = processStartTicks(w.pid).value_or(0);
  return w;
}

// Read again after a fork (a child has a pid and start time of its own).
const Writer& thisWriter() {
  static Writer cached;
  static uint64_t cachedFor = 0;
  if (cachedFor != uint64_t(::getpid())) {
    cached = readThisWriter();
    cachedFor = cached.pid;
  }
  return cached;
}

constexpr const char* kMarker = ".lucent-tmp.";

// A stem cut to `bytes` at most, at a character boundary of UTF-8, so that the temporary name stays
// below the 255 bytes a file name may have.
std::string shortened(std::string stem, size_t bytes) {
  if (stem.size() <= bytes) return stem;
  stem.resize(bytes);
  while (!stem.empty() && (static_cast<unsigned char>(stem.back()) & 0xC0) == 0x80) stem.pop_back();
  if (!stem.empty() && (static_cast<unsigned char>(stem.back()) & 0x80)) stem.pop_back();
  return stem;
}

void removeQuietly(const std::filesystem::path& path) {
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
}

// The writer a temporary name of Lucent's names, or nullopt when `name` is not one.
std::optional<Writer> writerOf(const std::string& name) {
  static const std::regex temporary(
      R"(\..*\.lucent-tmp\.([0-9a-f]{16})\.([0-9]{1,20})\.([0-9]{1,20})\.([0-9]{1,20})\.[0-9]{1,10}(\.[^.]*)?)");
  std::smatch m;
  if (!std::regex_match(name, m, temporary)) return std::nullopt;
  Writer w;
  auto number = [&](int group, uint64_t& value, int base) {
    const std::string text = m[group].str();
    const auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), value, base);
    return ec == std::errc() && p == text.data() + text.size();
  };
  if (!number(1, w.boot, 16) || !number(2, w.pidNamespace, 10) || !number(3, w.pid, 10) || !number(4, w.startTicks, 10))
    return std::nullopt;
  return w;
}

// A file's identity: its device and inode.
struct FileIdentity {
  uint64_t device = 0, inode = 0;
  bool operator==(const FileIdentity&) const = default;
};

// The identities `path` has: of the name itself (lstat: a symbolic link is its own) and of the file
// it leads to (stat); none where it does not exist.
std::vector<FileIdentity> identitiesOf(const std::filesystem::path& path) {
  std::vector<FileIdentity> ids;
  struct stat s {};
  if (::lstat(path.c_str(), &s) == 0) ids.push_back({uint64_t(s.st_dev), uint64_t(s.st_ino)});
  if (::stat(path.c_str(), &s) == 0) ids.push_back({uint64_t(s.st_dev), uint64_t(s.st_ino)});
  return ids;
}

struct AdmittedInput {
  std::string path;
  std::vector<FileIdentity> identities;
};

// The process's inputs, as admitInputFile admitted them.
struct InputRegistry {
  std::mutex mutex;
  std::vector<AdmittedInput> inputs;
};
InputRegistry& inputRegistry() {
  static InputRegistry registry;
  return registry;
}

bool shareAnIdentity(const std::vector<FileIdentity>& a, const std::vector<FileIdentity>& b) {
  for (const FileIdentity& x : a)
    for (const FileIdentity& y : b)
      if (x == y) return true;
  return false;
}

// While any write is under way (in any thread), SIGINT, SIGTERM and SIGHUP wait for it: each is
// recorded, and once the last write has renamed or removed its files the dispositions before the
// first write are restored and the recorded signals raised again, so that they act as they would
// have (end the process, set Python's or a render's stop flag, or nothing where ignored) with no
// temporary file left behind. Dispositions are process-wide, so this covers every thread, which
// blocking signals in the writing thread alone would not. SIGKILL still ends a write at once.
class SignalsWaitForWrites {
 public:
  SignalsWaitForWrites() {
    const std::lock_guard lock(mutex());
    if (depth()++ > 0) return;
    struct sigaction record {};
    record.sa_handler = &SignalsWaitForWrites::record;
    sigemptyset(&record.sa_mask);
    for (size_t i = 0; i < kSignals.size(); ++i) sigaction(kSignals[i], &record, &previous()[i]);
  }
  ~SignalsWaitForWrites() {
    const std::lock_guard lock(mutex());
    if (--depth() > 0) return;
    for (size_t i = 0; i < kSignals.size(); ++i) sigaction(kSignals[i], &previous()[i], nullptr);
    const unsigned pending = pending_.exchange(0);
    for (size_t i = 0; i < kSignals.size(); ++i)
      if (pending & (1u << i)) ::raise(kSignals[i]);
  }
  SignalsWaitForWrites(const SignalsWaitForWrites&) = delete;
  SignalsWaitForWrites& operator=(const SignalsWaitForWrites&) = delete;

 private:
  static constexpr std::array<int, 3> kSignals{SIGINT, SIGTERM, SIGHUP};
  static void record(int signal) {
    for (size_t i = 0; i < kSignals.size(); ++i)
      if (kSignals[i] == signal) pending_.fetch_or(1u << i);
  }
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static int& depth() {
    static int d = 0;
    return d;
  }
  static std::array<struct sigaction, kSignals.size()>& previous() {
    static std::array<struct sigaction, kSignals.size()> p{};
    return p;
  }
  static inline std::atomic<unsigned> pending_{0};
};

}  // namespace

std::string admitInputFile(const std::filesystem::path& path) {
  std::string problem = regularFileProblem(path);
  if (!problem.empty()) return problem;
  AdmittedInput input{path.string(), identitiesOf(path)};
  InputRegistry& registry = inputRegistry();
  const std::lock_guard lock(registry.mutex);
  for (AdmittedInput& known : registry.inputs) {
    if (known.identities == input.identities) return "";
    // Read again after it was replaced (an editor saving by rename, a script rewriting it): the
    // file it was is no longer the one that name leads to, so the registry keeps one entry per name
    // and does not grow with every reload.
    if (known.path == input.path) {
      known.identities = std::move(input.identities);
      return "";
    }
  }
  registry.inputs.push_back(std::move(input));
  return "";
}

std::string inputFileClash(const std::filesystem::path& path, const std::vector<std::string>& alsoInputs) {
  const std::vector<FileIdentity> target = identitiesOf(path);
  if (target.empty()) return "";  // nothing there: no input is
  auto clash = [](const std::string& input) { return "it is '" + input + "', a file this process reads"; };
  for (const std::string& input : alsoInputs)
    if (shareAnIdentity(target, identitiesOf(input))) return clash(input);
  InputRegistry& registry = inputRegistry();
  const std::lock_guard lock(registry.mutex);
  for (const AdmittedInput& input : registry.inputs)
    if (shareAnIdentity(target, input.identities)) return clash(input.path);
  return "";
}

std::filesystem::path temporaryPathFor(const std::filesystem::path& path) {
  static std::atomic<unsigned> counter{0};
  const Writer& w = thisWriter();
  char id[96];
  std::snprintf(id, sizeof id, "%s%016llx.%llu.%llu.%llu.%u", kMarker, static_cast<unsigned long long>(w.boot),
                static_cast<unsigned long long>(w.pidNamespace), static_cast<unsigned long long>(w.pid),
                static_cast<unsigned long long>(w.startTicks), counter++);
  const std::string extension = path.extension().string();
  const size_t room = 255 - std::min<size_t>(255, 1 + std::string(id).size() + extension.size());
  return path.parent_path() / ("." + shortened(path.stem().string(), room) + id + extension);
}

bool isAbandonedTemporaryFile(const std::string& name) {
  const std::optional<Writer> writer = writerOf(name);
  if (!writer) return false;
  const Writer& self = thisWriter();
  // Only a process of this boot of this machine, in this process-id namespace, can be looked up.
  if (writer->boot == 0 || writer->pidNamespace == 0 || writer->startTicks == 0 || self.boot == 0 ||
      self.pidNamespace == 0 || writer->boot != self.boot || writer->pidNamespace != self.pidNamespace)
    return false;
  if (writer->pid == self.pid && writer->startTicks == self.startTicks) return false;  // this process: alive
  if (!procIsOurs()) return false;
  const std::optional<uint64_t> started = processStartTicks(writer->pid);
  // No such process: /proc has no entry, and the kernel says so too (/proc mounted with hidepid
  // hides other users' processes, which kill answers with EPERM).
  if (!started) return ::kill(pid_t(writer->pid), 0) != 0 && errno == ESRCH;
  // The id now belongs to a process that started at another time; 0: its state could not be read.
  return *started != 0 && *started != writer->startTicks;
}

void removeStaleTemporaryFiles(const std::filesystem::path& directory) {
  std::error_code ec;
  for (std::filesystem::directory_iterator it(directory.empty() ? "." : directory, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::error_code typeError;
    if (it->is_regular_file(typeError) && isAbandonedTemporaryFile(name)) removeQuietly(it->path());
  }
}

void checkWritable(const std::filesystem::path& path, const std::string& what) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw std::runtime_error("cannot write " + what + " '" + path.string() + "': it is a directory");
  if (const std::string clash = inputFileClash(path); !clash.empty())
    throw std::runtime_error("cannot write " + what + " '" + path.string() + "': " + clash);
  // The probe is a temporary file too: a signal waits until it is removed.
  const SignalsWaitForWrites signalsWait;
  const std::filesystem::path probe = temporaryPathFor(path);
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    const std::string why = std::strerror(errno);
    throw std::runtime_error("cannot write " + what + " '" + path.string() + "': " + why);
  }
  ::close(fd);
  removeQuietly(probe);
  // In a sticky directory (/tmp), a file of another user cannot be replaced by a rename.
  struct stat dirStat {}, fileStat {};
  const std::filesystem::path dir = path.parent_path().empty() ? "." : path.parent_path();
  if (::geteuid() != 0 && ::stat(dir.c_str(), &dirStat) == 0 && (dirStat.st_mode & S_ISVTX) &&
      ::lstat(path.c_str(), &fileStat) == 0 && fileStat.st_uid != ::geteuid() && dirStat.st_uid != ::geteuid())
    throw std::runtime_error("cannot write " + what + " '" + path.string() +
                             "': it belongs to another user in a sticky directory");
}

void writeFilesAtomically(const std::vector<FileToWrite>& files) {
  const SignalsWaitForWrites signalsWait;
  // What would stop a rename, checked before anything is written or renamed.
  for (const FileToWrite& f : files) {
    std::error_code ec;
    if (std::filesystem::is_directory(f.path, ec))
      throw std::runtime_error("cannot write " + f.what + " '" + f.path.string() + "': it is a directory");
    if (const std::string clash = inputFileClash(f.path); !clash.empty())
      throw std::runtime_error("cannot write " + f.what + " '" + f.path.string() + "': " + clash);
  }
  std::vector<std::filesystem::path> temporary;
  auto removeAll = [&] {
    for (const auto& tmp : temporary) removeQuietly(tmp);
  };
  for (const FileToWrite& f : files) {
    removeStaleTemporaryFiles(f.path.parent_path());
    temporary.push_back(temporaryPathFor(f.path));
    try {
      f.write(temporary.back());
    } catch (const WriteFailure& e) {
      removeAll();
      throw std::runtime_error("cannot write " + f.what + " '" + f.path.string() + "': " + e.what());
    } catch (...) {
      removeAll();
      throw;
    }
  }
  for (size_t i = 0; i < files.size(); ++i) {
    std::error_code ec;
    std::filesystem::rename(temporary[i], files[i].path, ec);
    if (ec) {
      for (size_t j = i; j < files.size(); ++j) removeQuietly(temporary[j]);
      throw std::runtime_error("cannot write " + files[i].what + " '" + files[i].path.string() + "': " + ec.message());
    }
  }
}

void writeFileAtomically(const std::filesystem::path& path, const std::string& what,
                         const std::function<void(const std::filesystem::path& tmp)>& write) {
  writeFilesAtomically({{path, what, write}});
}

std::string regularFileProblem(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) return "not found";
  if (ec) return "cannot be read: " + ec.message();
  if (status.type() != std::filesystem::file_type::regular) return "is not a regular file";
  return "";
}

}  // namespace lucent
