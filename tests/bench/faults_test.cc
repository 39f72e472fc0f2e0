// Faults of long suites (issue #23 item 5): the output lock between
// processes (bench/io/output_lock.h) and the scheduler stopping at the first
// failed task. The end-to-end cases (SIGKILL, a second writer, a full disk)
// are tests/cli/bench_faults_test.sh.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "quasiroll/bench/harness/harness.h"
#include "quasiroll/bench/io/output_lock.h"
#include "test_support.h"

namespace quasiroll::bench {
namespace {

namespace fs = std::filesystem;

// A child process holding LockOutputDirectory(dir, part) until Release()
// (or until it is killed). fcntl locks do not conflict within one process,
// hence the fork.
class LockHolder {
 public:
  LockHolder(const std::string& dir, const std::string& part) {
    int ready[2], release[2];
    if (::pipe(ready) != 0 || ::pipe(release) != 0)
      throw std::runtime_error("pipe");
    pid_ = ::fork();
    if (pid_ == 0) {
      // Without the parent's ends the read below ends when the parent
      // closes `release` (or dies).
      ::close(ready[0]);
      ::close(release[1]);
      char c = 0;
      try {
        const auto locks = LockOutputDirectory(dir, part, "--out");
        c = 1;
        if (::write(ready[1], &c, 1) != 1) ::_exit(3);
        if (::read(release[0], &c, 1) < 0) ::_exit(4);
      } catch (...) {
        if (::write(ready[1], &c, 1) != 1) ::_exit(3);
        ::_exit(2);
      }
      ::_exit(0);
    }
    ::close(ready[1]);
    ::close(release[0]);
    release_ = release[1];
    char c = 0;
    locked_ = ::read(ready[0], &c, 1) == 1 && c == 1;
    ::close(ready[0]);
  }
  ~LockHolder() {
    if (pid_ > 0) Release();
  }
  bool locked() const { return locked_; }
  pid_t pid() const { return pid_; }
  void Release() {
    ::close(release_);
    ::waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }
  void Kill() {
    ::kill(pid_, SIGKILL);
    Release();
  }

 private:
  pid_t pid_ = -1;
  int release_ = -1;
  bool locked_ = false;
};

// The message of the OutputLockedError `fn` throws ("" if none).
template <typename Fn>
std::string Refusal(Fn fn) {
  try {
    fn();
  } catch (const OutputLockedError& e) {
    return e.what();
  }
  return "";
}

TEST(OutputLock, SecondWriterOfADirectoryIsRefusedNamingItAndTheHolder) {
  const fs::path dir = FreshTempDir("quasiroll_lock_whole_");
  LockHolder holder(dir.string(), "");
  ASSERT_TRUE(holder.locked());
  const std::string pid = "process " + std::to_string(holder.pid());
  for (const std::string& part :
       {std::string(), (dir / "shards/0-of-2").string()}) {
    const std::string what =
        Refusal([&] { LockOutputDirectory(dir.string(), part, "--out"); });
    EXPECT_NE(what.find("--out: output directory '" + dir.string() + "'"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find(pid), std::string::npos) << what;
  }
  holder.Release();
  EXPECT_NO_THROW(LockOutputDirectory(dir.string(), "", "--out"));
  fs::remove_all(dir);
}

TEST(OutputLock, ShardsShareADirectoryButNotTheirOwnSlice) {
  const fs::path dir = FreshTempDir("quasiroll_lock_shards_");
  const std::string shard0 = (dir / "shards/0-of-2").string();
  LockHolder holder(dir.string(), shard0);
  ASSERT_TRUE(holder.locked());
  EXPECT_NO_THROW(LockOutputDirectory(
      dir.string(), (dir / "shards/1-of-2").string(), "--out"));
  const std::string same =
      Refusal([&] { LockOutputDirectory(dir.string(), shard0, "--out"); });
  EXPECT_NE(same.find("'" + shard0 + "'"), std::string::npos) << same;
  EXPECT_NE(same.find("process " + std::to_string(holder.pid())),
            std::string::npos)
      << same;
  // A whole suite on DIR would rewrite what the shard writes there.
  EXPECT_NE(Refusal([&] { LockOutputDirectory(dir.string(), "", "--out"); }),
            "");
  fs::remove_all(dir);
}

TEST(OutputLock, AKilledHolderLeavesNoStaleLock) {
  const fs::path dir = FreshTempDir("quasiroll_lock_killed_");
  LockHolder holder(dir.string(), "");
  ASSERT_TRUE(holder.locked());
  EXPECT_NE(Refusal([&] { LockOutputDirectory(dir.string(), "", "--out"); }),
            "");
  holder.Kill();
  EXPECT_TRUE(fs::exists(dir / ".lock"));  // the file stays, the lock not
  EXPECT_NO_THROW(LockOutputDirectory(dir.string(), "", "--out"));
  fs::remove_all(dir);
}

// After a task throws (a write failure: every later run would fail too,
// after computing), no other task starts; the error reaches the caller.
TEST(ScheduleTasks, NoTaskStartsAfterOneThrew) {
  const int n = 8;
  std::vector<int> started;
  EXPECT_THROW(
      ScheduleTasks(std::vector<int>(n, 0), std::vector<bool>(n, false), 1,
                    [&](int k) {
                      started.push_back(k);
                      if (k == 2) throw FileWriteError("disk full");
                    }),
      FileWriteError);
  EXPECT_EQ(started, (std::vector<int>{0, 1, 2}));
}

}  // namespace
}  // namespace quasiroll::bench
