// Files written whole or not at all, and which temporary files a write may remove: only Lucent's own,
// and only those whose writer is proven gone.
#include <catch2/catch.hpp>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "lucent/core/files.h"
#include "test_support.h"

using namespace lucent;
namespace fs = std::filesystem;
using test::TempDir;

namespace {

// A child process that stays alive until released; its temporary name for `target` is known.
class ChildWriter {
 public:
  explicit ChildWriter(const fs::path& target) {
    int toParent[2], toChild[2];
    REQUIRE(::pipe(toParent) == 0);
    REQUIRE(::pipe(toChild) == 0);
    pid_ = ::fork();
    REQUIRE(pid_ >= 0);
    if (pid_ == 0) {
      // Only its own ends of the pipes: another child's release must reach that child alone.
      for (int fd = 3; fd < 1024; ++fd)
        if (fd != toParent[1] && fd != toChild[0]) ::close(fd);
      const std::string name = temporaryPathFor(target).filename().string();
      (void)!::write(toParent[1], name.data(), name.size());
      ::close(toParent[1]);
      char c;
      (void)!::read(toChild[0], &c, 1);  // until released
      ::_exit(0);
    }
    ::close(toParent[1]);
    ::close(toChild[0]);
    release_ = toChild[1];
    char buffer[512];
    const ssize_t n = ::read(toParent[0], buffer, sizeof buffer);
    ::close(toParent[0]);
    REQUIRE(n > 0);
    name_.assign(buffer, size_t(n));
  }
  ~ChildWriter() { finish(); }
  const std::string& name() const { return name_; }
  // Lets the child exit and waits for it: its temporary name is then abandoned.
  void finish() {
    if (pid_ <= 0) return;
    ::close(release_);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
  }

 private:
  pid_t pid_ = -1;
  int release_ = -1;
  std::string name_;
};

// `name` with its field `index` (0: boot, 1: pid namespace, 2: pid, 3: start time) replaced.
std::string withField(const std::string& name, int index, const std::string& value) {
  static const std::regex fields(R"((.*\.lucent-tmp\.)([0-9a-f]+)\.([0-9]+)\.([0-9]+)\.([0-9]+)(\..*))");
  std::smatch m;
  REQUIRE(std::regex_match(name, m, fields));
  std::string parts[4] = {m[2], m[3], m[4], m[5]};
  parts[index] = value;
  return m[1].str() + parts[0] + "." + parts[1] + "." + parts[2] + "." + parts[3] + m[6].str();
}

void touch(const TempDir& dir, const std::string& name) { std::ofstream(dir / name) << "someone's data"; }

}  // namespace

TEST_CASE("A temporary name says who writes it, keeps the extension and fits a file name") {
  const fs::path target = "/some/dir/out.exr";
  const fs::path tmp = temporaryPathFor(target);
  CHECK(tmp.parent_path() == target.parent_path());
  CHECK(tmp.extension() == ".exr");
  CHECK_THAT(tmp.filename().string(), Catch::StartsWith(".out.lucent-tmp."));
  CHECK(temporaryPathFor(target) != tmp);  // unique per call
  const std::string longStem(300, 'a');
  const fs::path longTmp = temporaryPathFor("/d/" + longStem + ".film");
  CHECK(longTmp.filename().string().size() <= 255);
  CHECK(longTmp.extension() == ".film");
  // A stem of multi-byte characters is cut at a character's boundary.
  std::string accents;
  for (int i = 0; i < 150; ++i) accents += "\xc3\xa9";  // é
  const std::string cut = temporaryPathFor("/d/" + accents + ".exr").filename().string();
  CHECK(cut.size() <= 255);
  const std::string stem = cut.substr(1, cut.find(".lucent-tmp.") - 1);
  CHECK(stem.size() % 2 == 0);
}

TEST_CASE("Only Lucent's temporary files whose writer is gone are abandoned") {
  TempDir dir;
  ChildWriter alive(dir.path / "out.exr");
  const std::string own = temporaryPathFor(dir.path / "out.exr").filename().string();
  SECTION("a running process's, this process's, and another program's files are not") {
    CHECK_FALSE(isAbandonedTemporaryFile(alive.name()));
    CHECK_FALSE(isAbandonedTemporaryFile(own));
    for (const std::string foreign :
         {".notes.tmp-4000000-1.txt", ".out.tmp-999999999-0.exr", ".x.tmp-99999999999999999999-0.exr", "out.exr",
          ".out.lucent-tmp.zz.1.2.3.0.exr", ".out.lucent-tmp.0123456789abcdef.1.2.3.exr"})
      CHECK_FALSE(isAbandonedTemporaryFile(foreign));
  }
  SECTION("a finished process's is, and so is one whose process id now names a later process") {
    ChildWriter finished(dir.path / "out.exr");
    finished.finish();
    CHECK(isAbandonedTemporaryFile(finished.name()));
    // The live child's id with another start time: the id was reused.
    CHECK(isAbandonedTemporaryFile(withField(alive.name(), 3, "1")));
  }
  SECTION("one from another machine or boot, or another process-id namespace, cannot be proven gone") {
    ChildWriter finished(dir.path / "out.exr");
    finished.finish();
    CHECK_FALSE(isAbandonedTemporaryFile(withField(finished.name(), 0, "0123456789abcdef")));
    CHECK_FALSE(isAbandonedTemporaryFile(withField(finished.name(), 1, "4026531111")));
    CHECK_FALSE(isAbandonedTemporaryFile(withField(finished.name(), 0, "0000000000000000")));
    CHECK_FALSE(isAbandonedTemporaryFile(withField(finished.name(), 3, "0")));
    CHECK_FALSE(isAbandonedTemporaryFile(withField(finished.name(), 2, "99999999999999999999")));
  }
}

TEST_CASE("A write removes abandoned temporary files beside it and nothing else") {
  TempDir dir;
  ChildWriter alive(dir.path / "out.exr"), finished(dir.path / "out.exr");
  finished.finish();
  const std::vector<std::string> kept = {".notes.tmp-4000000-1.txt", ".out.tmp-999999999-0.exr",
                                         ".x.tmp-99999999999999999999-0.exr", alive.name(),
                                         withField(finished.name(), 0, "0123456789abcdef")};
  for (const std::string& name : kept) touch(dir, name);
  touch(dir, finished.name());
  fs::create_directory(dir.path / withField(alive.name(), 3, "1"));  // a directory of that name: not a file
  writeFileAtomically(dir.path / "out.txt", "text", [](const fs::path& tmp) { std::ofstream(tmp) << "new"; });
  CHECK(fs::exists(dir.path / "out.txt"));
  CHECK_FALSE(fs::exists(dir.path / finished.name()));
  for (const std::string& name : kept) CHECK(fs::exists(dir.path / name));
  CHECK(fs::is_directory(dir.path / withField(alive.name(), 3, "1")));
}

TEST_CASE("checkWritable says before any work what would fail a write") {
  TempDir dir;
  CHECK_NOTHROW(checkWritable(dir.path / "a.exr", "-o"));
  CHECK(dir.entries().empty());  // its probe is gone
  fs::create_directory(dir.path / "taken.exr");
  CHECK_THROWS_WITH(checkWritable(dir.path / "taken.exr", "-o"), Catch::Contains("it is a directory"));
  CHECK_THROWS_WITH(checkWritable(dir.path / "missing" / "a.exr", "-o"), Catch::Contains("cannot write -o"));
  if (::geteuid() != 0) {  // root writes anywhere
    fs::create_directory(dir.path / "locked");
    fs::permissions(dir.path / "locked", fs::perms::owner_read | fs::perms::owner_exec);
    CHECK_THROWS_WITH(checkWritable(dir.path / "locked" / "a.exr", "-o"), Catch::Contains("Permission denied"));
    fs::permissions(dir.path / "locked", fs::perms::owner_all);
  }
}

TEST_CASE("No write replaces a file the process read, by whatever name it is reached") {
  TempDir dir;
  fs::create_directory(dir.path / "sub");
  std::ofstream(dir.path / "sub" / "texture.png") << "pixels";
  auto write = [](const fs::path& path) {
    writeFileAtomically(path, "an image", [](const fs::path& tmp) { std::ofstream(tmp) << "new"; });
  };
  fs::create_hard_link(dir.path / "sub" / "texture.png", dir.path / "hard.png");
  fs::create_symlink(dir.path / "sub" / "texture.png", dir.path / "soft.png");
  // Before it is read, it is any file.
  CHECK(inputFileClash(dir.path / "sub" / "texture.png").empty());
  REQUIRE(admitInputFile(dir.path / "sub" / ".." / "sub" / "texture.png").empty());
  for (const fs::path& name : {dir.path / "sub" / "texture.png", dir.path / "sub" / ".." / "sub" / "texture.png",
                               dir.path / "hard.png", dir.path / "soft.png"}) {
    INFO(name);
    CHECK_THAT(inputFileClash(name), Catch::Contains("a file this process reads"));
    CHECK_THROWS_WITH(write(name), Catch::Contains("a file this process reads"));
    CHECK_THROWS_WITH(checkWritable(name, "--png"), Catch::Contains("a file this process reads"));
  }
  std::ifstream in(dir.path / "sub" / "texture.png");
  CHECK(std::string(std::istreambuf_iterator<char>(in), {}) == "pixels");
  // A symbolic link read as input is protected as a name too: replacing it would cut the scene off
  // from its file.
  fs::create_symlink(dir.path / "elsewhere.png", dir.path / "link.png");
  std::ofstream(dir.path / "elsewhere.png") << "x";
  REQUIRE(admitInputFile(dir.path / "link.png").empty());
  CHECK_THROWS_WITH(write(dir.path / "link.png"), Catch::Contains("a file this process reads"));
  // Named by the caller before being read.
  std::ofstream(dir.path / "later.exr") << "x";
  CHECK_THAT(inputFileClash(dir.path / "later.exr", {(dir.path / "." / "later.exr").string()}),
             Catch::Contains("a file this process reads"));
  CHECK_NOTHROW(write(dir.path / "other.png"));
}

TEST_CASE("A name read again after its file was replaced protects the file it now leads to, not both") {
  // One entry per name: a process that reloads a scene thousands of times (a script, a fuzzer)
  // keeps a registry of its names, not of every file they ever led to.
  TempDir dir;
  std::ofstream(dir.path / "scene.json") << "first";
  REQUIRE(admitInputFile(dir.path / "scene.json").empty());
  fs::create_hard_link(dir.path / "scene.json", dir.path / "first.json");  // keeps the first file alive
  CHECK_THAT(inputFileClash(dir.path / "first.json"), Catch::Contains("a file this process reads"));
  fs::remove(dir.path / "scene.json");
  std::ofstream(dir.path / "scene.json") << "second";
  REQUIRE(admitInputFile(dir.path / "scene.json").empty());
  CHECK_THAT(inputFileClash(dir.path / "scene.json"), Catch::Contains("a file this process reads"));
  CHECK(inputFileClash(dir.path / "first.json").empty());
}

TEST_CASE("Only regular files are admitted as inputs") {
  TempDir dir;
  REQUIRE(::mkfifo((dir.path / "pipe.bin").c_str(), 0600) == 0);
  CHECK(admitInputFile(dir.path / "pipe.bin") == "is not a regular file");
  CHECK(admitInputFile(dir.path) == "is not a regular file");
  CHECK(admitInputFile(dir.path / "missing") == "not found");
  CHECK(admitInputFile("/dev/zero") == "is not a regular file");
}
