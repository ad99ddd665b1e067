#include "core/lab/stage_cache.hpp"

#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <system_error>

#include "core/common/bytes.hpp"
#include "core/common/error.hpp"
#include "core/lab/protocol.hpp"

namespace demcal::lab {
namespace {

/// FNV-1a, 64 bits: a file name for an identity (the record itself holds the identity, so a
/// collision costs a miss, never a wrong record).
std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace

std::string protocol_line(std::string_view test) {
  return "demcal lab protocol " + std::to_string(protocol_version(test)) + "\n";
}

StageCache::StageCache(std::filesystem::path dir) : dir_(std::move(dir)) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec || !std::filesystem::is_directory(dir_))
    throw InputError(dir_.string(), "cannot be used as the stage cache: " + ec.message());
}

std::filesystem::path StageCache::file_for(const std::string& identity) const {
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.stage",
                static_cast<unsigned long long>(fnv1a(identity)));
  return dir_ / name;
}

std::optional<std::string> StageCache::find(const std::string& identity) const {
  std::ifstream in(file_for(identity), std::ios::binary);
  if (!in) return std::nullopt;
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  try {
    ByteReader reader(bytes, "stage cache");
    std::string kept_identity, record;
    reader.get(kept_identity);
    if (kept_identity != identity) return std::nullopt;
    reader.get(record);
    reader.expect_end();
    return record;
  } catch (const InputError&) {
    return std::nullopt;
  }
}

void StageCache::keep(const std::string& identity, const std::string& record) const {
  ByteWriter writer;
  writer.put(identity);
  writer.put(record);
  const std::string bytes = writer.take();
  const auto target = file_for(identity);
  // A name of this process and call: two runs keeping one record at once never share a file.
  static std::atomic<unsigned> calls{0};
  char suffix[64];
  std::snprintf(suffix, sizeof suffix, ".%ld.%u.tmp", static_cast<long>(::getpid()), calls++);
  auto temporary = target;
  temporary += suffix;
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) {
      std::cerr << "stage cache: could not write " << temporary << "\n";
      return;
    }
  }
  std::error_code ec;
  std::filesystem::rename(temporary, target, ec);
  if (ec) {
    std::cerr << "stage cache: could not keep " << target << ": " << ec.message() << "\n";
    std::filesystem::remove(temporary, ec);
  }
}

}  // namespace demcal::lab
