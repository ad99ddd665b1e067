#pragma once
// Work that runs share, kept once (docs/lab-tests.md, "Work done once"): a record of a stage a
// run reached, kept in a directory under the identity of everything that acted on the run up to
// it (the lab protocol's version, the material, the settings, the seed, the threads), so that a
// run that would compute the same stage takes the record instead. Records are the bytes of
// sim::World::save_state and the stage's own fields (core/common/bytes.hpp): read back by the
// same build on the same kind of machine, and then the run goes on to the same bits as the run
// that made them. A record holds its whole identity and is taken only when that matches exactly
// (the file name is a hash of it); a file that cannot be read counts as absent.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace demcal::lab {

class StageCache {
 public:
  /// Records in `dir` (created if missing); an InputError naming the directory when it cannot
  /// be made.
  explicit StageCache(std::filesystem::path dir);

  /// The record kept under `identity`, if any.
  std::optional<std::string> find(const std::string& identity) const;
  /// Keeps `record` under `identity` (written to a temporary file and renamed, so a reader never
  /// sees half a record); a failure to write is reported on stderr and otherwise ignored: the
  /// cache saves work, it never decides a result.
  void keep(const std::string& identity, const std::string& record) const;

  const std::filesystem::path& directory() const { return dir_; }

 private:
  std::filesystem::path file_for(const std::string& identity) const;
  std::filesystem::path dir_;
};

/// The first line of every identity: the protocol version (core/lab/protocol.hpp) of the test
/// whose stage it is, so a record made under another protocol is never taken.
std::string protocol_line(std::string_view test);

}  // namespace demcal::lab
