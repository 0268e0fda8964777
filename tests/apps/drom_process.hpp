#pragma once
// Runs the drom binary under test and captures its exit code and output (stdout and stderr).
#include <array>
#include <cstdio>
#include <string>
#include <sys/wait.h>

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
