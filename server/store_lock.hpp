#pragma once
// One coordinator per store: an exclusive lock (flock) on FILE.lock next to the SQLite file,
// held for as long as the store is open, with the holder's pid written in it. Two coordinators
// on one file would both lease its jobs: each keeps its lease deadlines in memory, so each
// would give the other's running jobs out again. The kernel releases the lock when the process
// ends, however it ends (a SIGKILLed coordinator leaves no stale lock).
#include <optional>
#include <string>

namespace demcal::server {

class StoreLock {
 public:
  /// Takes the lock of `db_path` (nothing for ":memory:"). Throws std::runtime_error naming
  /// the file and the holder's pid when another store holds it.
  explicit StoreLock(const std::string& db_path);
  /// Who holds a store's lock: the pid its lock file names ("" when none) and since when (the
  /// lock file's modification time, wall-clock seconds: its holder wrote its pid on opening).
  struct Holder {
    std::string pid;
    double since = 0.0;
  };
  /// Whether another process holds the lock of `db_path` now, and who; nothing when the store is
  /// free (or has no lock file yet).
  static std::optional<Holder> holder(const std::string& db_path);
  ~StoreLock();
  StoreLock(const StoreLock&) = delete;
  StoreLock& operator=(const StoreLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace demcal::server
