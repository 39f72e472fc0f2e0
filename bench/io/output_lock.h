// Advisory locks on output directories (issue #23, item 5): two processes
// computing the same results into one directory would overwrite each other's
// runs.csv / atlas.csv and interleave their partial files, so the second one
// stops before it writes anything. Shards of one suite are designed to share
// a directory: each holds DIR shared and its own DIR/shards/I-of-N
// exclusively, so shards coexist while a second process of the same shard,
// or an unsharded process on DIR, is refused.
//
// POSIX record locks (fcntl F_SETLK on DIR/.lock, a write lock on byte 0):
// the kernel releases them when the process ends however it ends (SIGKILL
// included), so a killed job never leaves a stale lock, and F_GETLK names
// the holder's pid. They work across NFS with lockd. They are per process:
// threads of one process never conflict (the harness tests run suites side
// by side in one process), and closing any descriptor of the lock file
// would drop the process's lock, which is why only this class opens it. The
// file stays after the process ends (removing it would let a waiting process
// lock an unlinked inode while a new one locks a fresh file).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace quasiroll {

// Another process holds a conflicting lock: misuse of the output location
// (the CLI exits 2, docs/cli.md), not an I/O failure.
class OutputLockedError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// One lock on DIR/.lock for the lifetime of the object (movable, not
// copyable).
class OutputLock {
 public:
  enum class Mode { kExclusive, kShared };
  // Creates DIR if needed and locks DIR/.lock without waiting. Throws
  // OutputLockedError naming DIR and the holder's pid when a conflicting lock
  // is held, std::runtime_error naming the path when DIR or the lock file
  // cannot be created.
  OutputLock(const std::string& dir, Mode mode);
  ~OutputLock();
  OutputLock(OutputLock&& other) noexcept;
  OutputLock& operator=(OutputLock&& other) noexcept;
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

// The locks of one writer: DIR exclusively when `part_dir` is empty (a whole
// suite or atlas); else DIR shared and `part_dir` (e.g. DIR/shards/0-of-4)
// exclusively. `flag` names the option in the error ("--out").
std::vector<OutputLock> LockOutputDirectory(const std::string& dir,
                                            const std::string& part_dir,
                                            const std::string& flag);

}  // namespace quasiroll
