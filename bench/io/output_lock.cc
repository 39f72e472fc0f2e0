#include "quasiroll/bench/io/output_lock.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>

namespace quasiroll {

namespace fs = std::filesystem;

namespace {

struct flock WholeFileLock(OutputLock::Mode mode) {
  struct flock lock {};
  lock.l_type = mode == OutputLock::Mode::kExclusive ? F_WRLCK : F_RDLCK;
  lock.l_whence = SEEK_SET;
  lock.l_start = 0;
  lock.l_len = 0;  // to the end of the file, however long it grows
  return lock;
}

}  // namespace

OutputLock::OutputLock(const std::string& dir, Mode mode)
    : path_((fs::path(dir) / ".lock").string()) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec)
    throw std::runtime_error("cannot create directory '" + dir +
                             "': " + ec.message());
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw std::runtime_error("cannot open lock file '" + path_ +
                             "': " + std::strerror(errno));
  // The holder may release between a refused F_SETLK and F_GETLK (then
  // F_GETLK reports no conflict): try again a few times.
  for (int attempt = 0; attempt < 5; ++attempt) {
    struct flock lock = WholeFileLock(mode);
    if (::fcntl(fd_, F_SETLK, &lock) == 0) return;
    const int err = errno;
    if (err != EACCES && err != EAGAIN) {
      ::close(fd_);
      fd_ = -1;
      throw std::runtime_error("cannot lock '" + path_ +
                               "': " + std::strerror(err));
    }
    struct flock holder = WholeFileLock(mode);
    if (::fcntl(fd_, F_GETLK, &holder) == 0 && holder.l_type == F_UNLCK)
      continue;
    ::close(fd_);
    fd_ = -1;
    const std::string who = holder.l_pid > 0
                                ? "process " + std::to_string(holder.l_pid)
                                : std::string("another process");
    throw OutputLockedError(
        "output directory '" + dir + "' is in use by " + who + " (lock " +
        path_ +
        "): another quasiroll process writes the same results there; wait "
        "for it to end or choose another directory");
  }
  ::close(fd_);
  fd_ = -1;
  throw std::runtime_error("cannot lock '" + path_ +
                           "': the lock kept changing hands");
}

OutputLock::~OutputLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

OutputLock::OutputLock(OutputLock&& other) noexcept
    : path_(std::move(other.path_)), fd_(std::exchange(other.fd_, -1)) {}

OutputLock& OutputLock::operator=(OutputLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(other.path_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

std::vector<OutputLock> LockOutputDirectory(const std::string& dir,
                                            const std::string& part_dir,
                                            const std::string& flag) {
  std::vector<OutputLock> locks;
  try {
    if (part_dir.empty()) {
      locks.emplace_back(dir, OutputLock::Mode::kExclusive);
    } else {
      locks.emplace_back(dir, OutputLock::Mode::kShared);
      locks.emplace_back(part_dir, OutputLock::Mode::kExclusive);
    }
  } catch (const OutputLockedError& e) {
    throw OutputLockedError(flag + ": " + e.what());
  }
  return locks;
}

}  // namespace quasiroll
