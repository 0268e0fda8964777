#pragma once
// The drom subcommands. Each parses nothing itself (main.cpp does), calls the library and prints; it
// takes the shared options and returns the process exit code.
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
  // drom offline / truth
  bool replan = false;   // drom run: a finishing pass re-planned on the predicted final shape
  bool resume = false;   // continue an interrupted run in --out
  int stop_after = -1;   // solve at most this many stations in this invocation, then stop (batch, tests)
  int threads = 0;       // 0: one per hardware thread
  int frames = -1;       // full-field VTK frames; -1: 10 for truth, none for offline
  std::string stations;  // "a:b": only these stations, into the checkpoint folder (drom merge after)
  std::string merge_kind = "offline";  // drom merge: the slices of drom offline or of drom truth
  long long export_ccx = -1;           // drom offline / truth: write this station as a CalculiX deck instead
  // drom reduce (case_path holds the database)
  double tolerance = 1e-3;          // mm, POD truncation bound
  double history_tolerance = -1;    // mm, all space-time compressions together; -1: tolerance / 2
  double profile_scale = -1;        // MPa per unit profile; -1: the case's largest coefficient
  int max_rank = -1;
  std::string prior_mean = "case";  // the prior's mean: "case" ([stress]'s coefficients) or "zero"
  double top_margin = -1;           // mm around the pocket of the stock's top to keep; < 0: none
  // drom study
  std::string study_parameter;
  std::vector<double> study_values;
  // drom machine (case_path holds the program)
  std::string machine = "vmc_3axis";          // a machine file or a shipped machine's name
  std::string reader = "auto";                 // auto, plain or rs274
  std::vector<std::string> tool_diameters;     // "T=D" (mm), for cutter compensation read by rs274
  std::vector<std::string> subroutine_paths;   // searched by rs274 for O<name> call
  double sample_period = -1;                   // s between axes.csv rows
  // drom copy (case_path holds the cloud)
  std::optional<std::filesystem::path> settings;  // the settings file; none: the defaults
  std::string tool;                               // the finishing tool; empty: the settings'
  std::string copy_machine;                       // empty: the settings'
};

int run_command(const CommandOptions& options);    // drom run
int layer_command(const CommandOptions& options);  // drom layer
int study_command(const CommandOptions& options);  // drom study
int mesh_command(const CommandOptions& options);   // drom mesh
int check_command(const CommandOptions& options);  // drom check
int removal_command(const CommandOptions& options);  // drom removal
int offline_command(const CommandOptions& options);  // drom offline
int truth_command(const CommandOptions& options);    // drom truth
int merge_command(const CommandOptions& options);    // drom merge
int reduce_command(const CommandOptions& options);   // drom reduce
int deviation_command(const CommandOptions& options);  // drom deviation
int machine_command(const CommandOptions& options);    // drom machine
int copy_command(const CommandOptions& options);       // drom copy
int finish_command(const CommandOptions& options);     // drom finish
int orient_command(const CommandOptions& options);     // drom orient

}  // namespace drom::app
