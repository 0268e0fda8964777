#pragma once
// Runs the drom binary under test and captures its exit code and output (stdout and stderr); or starts
// it as a child to be killed (spawn_drom, wait_drom).
#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

struct DromResult {
  int exit_code;
  std::string output;
};

inline DromResult run_drom(const std::string& args, const std::string& binary = DROM_BINARY) {
  const std::string cmd = binary + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), pipe)) out += buf.data();
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// Starts drom with `a`, its output appended to `log`.
inline pid_t spawn_drom(const std::vector<std::string>& a, const std::filesystem::path& log, const char* binary = DROM_BINARY) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    ::dup2(fd, 1), ::dup2(fd, 2);
    std::vector<char*> argv = {const_cast<char*>(binary)};
    for (const auto& s : a) argv.push_back(const_cast<char*>(s.c_str()));
    argv.push_back(nullptr);
    ::execv(binary, argv.data());
    ::_exit(127);
  }
  return pid;
}

// The exit code, or -signal.
inline int wait_drom(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}
