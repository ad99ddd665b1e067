#pragma once
// Child processes for the service tests: spawn with output to a log file, signal, wait with a
// time bound. Every wait in these tests is bounded so a hang fails instead of blocking CI.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace demcal::test {

class Process {
 public:
  /// Standard output and error go to `log`, or error to `error_log` when one is given (to read
  /// a command's standard output alone).
  Process(std::vector<std::string> argv, const std::string& log, const std::string& error_log = "")
      : log_(log) {
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      dup2(fd, 1);
      dup2(error_log.empty() ? fd : open(error_log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644),
           2);
      std::vector<char*> args;
      for (auto& a : argv) args.push_back(a.data());
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
  }
  ~Process() {
    if (running()) {
      kill(pid_, SIGKILL);
      wait_exit(5.0);
    }
  }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return pid_; }
  bool running() {
    if (exited_) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      exited_ = true;
      status_ = status;
      return false;
    }
    return true;
  }
  void signal(int sig) { kill(pid_, sig); }
  /// Exit status (WEXITSTATUS, or 128 + signal), or -1 if still running after `seconds`.
  int wait_exit(double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (running()) {
      if (std::chrono::steady_clock::now() > end) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return WIFEXITED(status_) ? WEXITSTATUS(status_) : 128 + WTERMSIG(status_);
  }
  std::string log() const {
    std::ifstream in(log_);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }

 private:
  pid_t pid_ = -1;
  std::string log_;
  bool exited_ = false;
  int status_ = 0;
};

/// Polls `done` every `poll` seconds (20 ms unless a check is costly) for at most `seconds`.
inline bool wait_until(const std::function<bool()>& done, double seconds, double poll = 0.02) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::duration<double>(poll));
  }
  return done();
}

/// `spec_text` written to `dir`/spec.yaml (`dir` made afresh) and run by the embedded default,
/// `cli run` with two one-thread workers and the work directory `dir`/work; its standard output
/// and error go to `dir`/run.log. The caller waits for it.
inline Process embedded_run(const std::string& cli, const std::filesystem::path& dir,
                            const std::string& spec_text) {
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string spec = (dir / "spec.yaml").string();
  std::ofstream(spec) << spec_text;
  return Process(
      {cli, "run", spec, "--workdir", (dir / "work").string(), "--workers", "2", "--threads", "1"},
      (dir / "run.log").string());
}

}  // namespace demcal::test
