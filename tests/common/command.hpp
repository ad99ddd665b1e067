#pragma once
// Running a shell command from a test: its standard output and exit status.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace demcal::test {

struct CommandResult {
  int exit_code = -1;  ///< the command's exit status; -1 if it did not exit normally
  std::string out;     ///< its standard output (add " 2>&1" to the command for errors too)
};

/// Runs `cmd` through the shell and waits for it.
inline CommandResult run_command(const std::string& cmd) {
  CommandResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 65536> buf;
  while (std::size_t n = std::fread(buf.data(), 1, buf.size(), pipe)) r.out.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace demcal::test
