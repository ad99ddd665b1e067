#pragma once
// What build this is, for the records that outlive it (a campaign journal's first line):
// defined in a file cmake/BuildInfo.cmake writes at every build.
namespace demcal::server {

/// The project's version (CMake's PROJECT_VERSION).
const char* build_version();
/// `git describe --always --dirty` of the source tree it was built from; "unknown" outside git.
const char* build_commit();

}  // namespace demcal::server
