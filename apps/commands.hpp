#pragma once
// The drom subcommands. Each takes the shared options and returns the process exit code.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace drom::app {

struct CommandOptions {
  std::optional<std::filesystem::path> case_path;  // empty: the embedded flat-plate case
  std::vector<std::string> overrides;              // "key=value"
  std::filesystem::path out = "out";
  bool quiet = false;
};

int run_command(const CommandOptions& options);    // drom run
int mesh_command(const CommandOptions& options);   // drom mesh
int check_command(const CommandOptions& options);  // drom check
int removal_command(const CommandOptions& options);  // drom removal

}  // namespace drom::app
