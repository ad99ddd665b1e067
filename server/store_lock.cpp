#include "server/store_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace demcal::server {
namespace {

/// The pid the lock file names (what its holder wrote), or "" when it names none.
std::string holder_pid(int fd) {
  char buf[32] = {};
  const ssize_t n = ::pread(fd, buf, sizeof buf - 1, 0);
  if (n <= 0) return {};
  std::string pid(buf, static_cast<std::size_t>(n));
  pid.erase(pid.find_last_not_of(" \n") + 1);
  return pid;
}

/// Replaces the lock file's content with this process's pid; false if it could not.
bool write_own_pid(int fd) {
  const std::string pid = std::to_string(::getpid()) + "\n";
  return ::ftruncate(fd, 0) == 0 &&
         ::pwrite(fd, pid.data(), pid.size(), 0) == static_cast<ssize_t>(pid.size());
}

}  // namespace

StoreLock::StoreLock(const std::string& db_path) {
  if (db_path.empty() || db_path == ":memory:") return;
  const std::string path = db_path + ".lock";
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (fd_ < 0)
    throw std::runtime_error("cannot open the lock file " + path + " of " + db_path + ": " +
                             std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    const std::string pid = holder_pid(fd_);
    ::close(fd_);
    if (error == EWOULDBLOCK)
      throw std::runtime_error(
          "refusing to open " + db_path + ": another coordinator" +
          (pid.empty() ? std::string() : " (pid " + pid + ")") + " has it open (lock " + path +
          "); one coordinator per file: stop that one, or give this one another file");
    throw std::runtime_error("cannot lock " + path + ": " + std::strerror(error));
  }
  // The pid only serves the message of a coordinator refused; the lock holds without it.
  (void)write_own_pid(fd_);
}

std::optional<StoreLock::Holder> StoreLock::holder(const std::string& db_path) {
  if (db_path.empty() || db_path == ":memory:") return std::nullopt;
  const int fd = ::open((db_path + ".lock").c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  // A shared lock is refused while a store holds the exclusive one; taken, it is let go at once.
  std::optional<Holder> held;
  if (::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK) {
    struct stat st {};
    held = Holder{holder_pid(fd), ::fstat(fd, &st) == 0 ? double(st.st_mtim.tv_sec) +
                                                              1e-9 * double(st.st_mtim.tv_nsec)
                                                        : 0.0};
  }
  ::close(fd);
  return held;
}

StoreLock::~StoreLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the descriptor releases the lock
}

}  // namespace demcal::server
