// drom: distortion-aware machining of thin parts. See README.md and docs/.
#include "apps/commands.hpp"
#include "support/heap_policy.hpp"
#include "support/input_error.hpp"
#include "support/version.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace {

using drom::app::CommandOptions;

// A message in one write: under mpirun every rank may say it at once, and the launcher forwards
// each write whole (piecewise writes came out interleaved).
void say_once(const std::string& message) {
  std::fflush(stdout);
  std::fwrite(message.data(), 1, message.size(), stderr);
}

// What the command line fills in: the options the subcommands share, and the one positional argument
// (a case, a database, a program or a cloud).
struct Arguments {
  CommandOptions options;
  std::string case_path;
};

// Options are registered in the order `--help` lists them: the subcommand's input, then --out and
// --quiet, then its own settings.
void add_case_input(CLI::App& cmd, Arguments& a) {
  cmd.add_option("case", a.case_path, "case file (TOML); see cases/ and docs/case-files.md");
  cmd.add_option("--set", a.options.overrides, "override a case value, e.g. --set mesh.nx=20 (repeatable)")->take_all();
}

// --out's default is the subcommand's own (Subcommand::out), set after registration: one variable
// serves every subcommand, so a default captured from it would be whichever was registered last.
void add_output(CLI::App& cmd, Arguments& a, const std::string& out_help = "output folder") {
  cmd.add_option("--out", a.options.out, out_help);
  cmd.add_flag("--quiet", a.options.quiet, "no progress or table, only files");
}

void add_case_command(CLI::App& cmd, Arguments& a) {
  add_case_input(cmd, a);
  add_output(cmd, a);
}

void add_run(CLI::App& cmd, Arguments& a) {
  add_case_command(cmd, a);
  cmd.add_flag("--replan", a.options.replan,
               "re-plan a finishing pass on the predicted final shape, sampled as a cloud, and report its distance to the truth");
  cmd.add_option("--threads", a.options.threads, "the offline-and-truth pass's worker threads, per rank (default: one per hardware thread)")
      ->check(CLI::PositiveNumber);
}

void add_study(CLI::App& cmd, Arguments& a) {
  add_case_command(cmd, a);
  cmd.add_option("--param", a.options.study_parameter,
                 "the parameter: noise, angle, refresh, calibration, desync, amplitude or seed (the noise draw)")
      ->required();
  cmd.add_option("--values", a.options.study_values, "its values, e.g. --values 0,0.02,0.05")->required()->delimiter(',');
}

// drom offline and drom truth.
void add_job(CLI::App& cmd, Arguments& a) {
  add_case_command(cmd, a);
  CommandOptions& o = a.options;
  cmd.add_flag("--resume", o.resume, "continue the interrupted run in --out (refuses a different case)");
  cmd.add_option("--stop-after", o.stop_after, "solve at most N stations in this invocation, then stop (resume later)")
      ->check(CLI::NonNegativeNumber);
  cmd.add_option("--threads", o.threads, "worker threads (default: one per hardware thread)")->check(CLI::PositiveNumber);
  cmd.add_option("--frames", o.frames, "full-field VTK frames over the stations (default: 10 for truth, 0 for offline)")
      ->check(CLI::NonNegativeNumber);
  cmd.add_option("--stations", o.stations,
                 "only stations a to b - 1 (a:b, a: or :b), into --out's checkpoint folder; drom merge writes the database once all are there");
  cmd.add_option("--export-ccx", o.export_ccx,
                 "instead of the job: station K (0-based) as a CalculiX deck (station_K.inp, run ccx -i station_K) with drom's answer beside it "
                 "(station_K_drom.csv)")
      ->check(CLI::NonNegativeNumber);
}

void add_merge(CLI::App& cmd, Arguments& a) {
  add_case_command(cmd, a);
  CommandOptions& o = a.options;
  cmd.add_option("--kind", o.merge_kind, "the slices of drom offline or of drom truth")
      ->capture_default_str()
      ->check(CLI::IsMember({"offline", "truth"}));
  cmd.add_option("--threads", o.threads, "worker threads for the final shape (default: one per hardware thread)")->check(CLI::PositiveNumber);
  cmd.add_option("--frames", o.frames, "as the slices were run with (default: 10 for truth, 0 for offline)")->check(CLI::NonNegativeNumber);
}

void add_reduce(CLI::App& cmd, Arguments& a) {
  CommandOptions& o = a.options;
  cmd.add_option("database", a.case_path, "database.h5 written by drom offline")->required();
  cmd.add_option("--tol", o.tolerance, "POD truncation: max-norm error bound, mm (seed eq. 2.9)")->capture_default_str()->check(CLI::PositiveNumber);
  cmd.add_option("--history-tol", o.history_tolerance, "space-time compression of all basis histories together, mm (default: --tol / 2)")
      ->check(CLI::PositiveNumber);
  cmd.add_option("--scale", o.profile_scale, "plausible amplitude per unit profile, MPa (default: the case's largest coefficient)")
      ->check(CLI::PositiveNumber);
  cmd.add_option("--max-rank", o.max_rank, "cap on the number of POD modes")->check(CLI::PositiveNumber);
  cmd.add_option("--prior-mean", o.prior_mean, "the prior's mean: the case's [stress] profile, or zero")
      ->capture_default_str()
      ->check(CLI::IsMember({"case", "zero"}));
  cmd.add_option("--top-margin", o.top_margin,
                 "also keep the stock's top within this many mm of the pocket (what the laser reads ahead of the cut and around the "
                 "pocket); default: the machined floor only")
      ->check(CLI::NonNegativeNumber);
  add_output(cmd, a, "model file (.h5), or a folder for model.h5");
}

void add_copy(CLI::App& cmd, Arguments& a) {
  CommandOptions& o = a.options;
  cmd.add_option("cloud", a.case_path, "the scanned cloud: XYZ/CSV (x y z [nx ny nz]), PLY (ascii or binary) or PCD (ascii, binary or binary_compressed)")->required();
  cmd.add_option("--settings", o.settings, "settings file (TOML; docs/case-files.md, \"drom copy\"); default: the seed's hip run");
  cmd.add_option("--tool", o.tool, "finishing tool: ball:D, torus:D:r or flat:D (mm); default: the settings' (ball:6)");
  cmd.add_option("--machine", o.copy_machine, "machine file (TOML) or shipped machine; default: the settings' (ucp710_like)");
  cmd.add_option("--set", o.overrides, "override a setting, e.g. --set packets.coverage=0.9 (repeatable)")->take_all();
  add_output(cmd, a);
}

void add_finish(CLI::App& cmd, Arguments& a) {
  add_case_command(cmd, a);
  cmd.add_option("--threads", a.options.threads, "K values optimised at once (default: one per hardware thread)")->check(CLI::PositiveNumber);
  cmd.add_flag("--resume", a.options.resume,
               "take up a killed run's work in OUT.partial, or reuse the finished K values of the last complete run in OUT (default: start afresh)");
}

void add_orient(CLI::App& cmd, Arguments& a) {
  add_case_command(cmd, a);
  cmd.add_option("--threads", a.options.threads, "passes integrated and poses checked at once (default: one per hardware thread)")
      ->check(CLI::PositiveNumber);
}

void add_machine(CLI::App& cmd, Arguments& a) {
  CommandOptions& o = a.options;
  cmd.add_option("program", a.case_path, "G-code (.ngc, .nc, ...) or CL data (.apt, .cl, .cls, .csv)")->required();
  cmd.add_option("--machine", o.machine, "machine file (TOML), or a shipped machine: vmc_3axis, ucp710_like, gantry_head_ac")->capture_default_str();
  cmd.add_option("--set", o.overrides, "override a machine value, e.g. --set setup.tool_length=80 (repeatable)")->take_all();
  cmd.add_option("--reader", o.reader, "auto: drom's reader for the plain subset, LinuxCNC's rs274 otherwise")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "plain", "rs274"}));
  cmd.add_option("--tool-diameter", o.tool_diameters, "T=D: tool T's diameter in mm, for cutter compensation (repeatable)")->take_all();
  cmd.add_option("--subroutine-path", o.subroutine_paths, "a folder rs274 searches for O<name> call (repeatable)")->take_all();
  cmd.add_option("--sample-period", o.sample_period, "seconds between rows of axes.csv (default: the interpolation cycle)")
      ->check(CLI::PositiveNumber);
  add_output(cmd, a);
}

struct Subcommand {
  const char* name;
  const char* out;  // its own default output folder
  const char* help;
  void (*add)(CLI::App&, Arguments&);
  int (*run)(const CommandOptions&);
};

// In the order `drom --help` lists them.
const Subcommand kSubcommands[] = {
    {"run", "out", "the closed loop on a case (default: the embedded flat-plate case): offline, model, truth, corrected machining", add_run,
     drom::app::run_command},
    {"study", "out/study", "sweep one closed-loop parameter (noise, angle, refresh, calibration, desync, amplitude, seed) and tabulate the headline errors",
     add_study, drom::app::study_command},
    {"layer", "out/layer", "the FE core on uniform layer removal, against the closed form", add_case_command, drom::app::layer_command},
    {"removal", "out/removal", "compute the material each tool station removes, on the case's mesh", add_case_command, drom::app::removal_command},
    {"offline", "out/offline", "simulate the machining once per unit stress profile: the snapshot database (B1, B2)", add_job, drom::app::offline_command},
    {"truth", "out/truth", "simulate the machining for the case's own stress profile, with full fields", add_job, drom::app::truth_command},
    {"merge", "out/offline", "assemble database.h5 from the slices that drom offline / truth --stations a:b left in --out's checkpoint folder", add_merge,
     drom::app::merge_command},
    {"reduce", "out/model", "compress an offline database into the light model the online predictor loads", add_reduce, drom::app::reduce_command},
    {"deviation", "out/deviation", "learn an unknown blank's deviation from laser profiles during the approach (seed chapter 2)", add_case_command,
     drom::app::deviation_command},
    {"copy", "out/copy", "copy a scanned part from its point cloud by 3+2 machining: normals, visibility, packets, roughing and finishing per packet, G-code",
     add_copy, drom::app::copy_command},
    {"finish", "out/finish", "finishing paths on a free-form surface in the least time under a scallop bound (zoning, tool choice, 3-axis or 3+2)", add_finish,
     drom::app::finish_command},
    {"orient", "out/orient", "collision-free 5-axis tool axis along fixed CL paths from repulsive fields (seed 000), proved by a clearance check and put on a machine",
     add_orient, drom::app::orient_command},
    {"mesh", "out/mesh", "mesh the case's part and write it with its clamps to VTK", add_case_command, drom::app::mesh_command},
    {"check", "out/check", "validate a case file and print it with every override applied", add_case_command, drom::app::check_command},
    {"machine", "out/machine", "a program (G-code or CL data) on a machine: travel, singularities, the feed it really reaches, the limiting axes, the cycle time",
     add_machine, drom::app::machine_command},
};

using Registered = std::vector<std::pair<CLI::App*, const Subcommand*>>;

// The exit code when parsing ends the program (help, version, a usage error); nothing otherwise.
std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  }
  return std::nullopt;
}

// Runs the subcommand given; its errors become the exit codes apps/README.md lists.
int run_parsed(const Registered& commands, CommandOptions options) {
  for (const auto& [cmd, sub] : commands) {
    if (!cmd->parsed()) continue;
    if (cmd->count("--out") == 0) options.out = sub->out;
    try {
      return sub->run(options);
    } catch (const drom::InputError& e) {
      say_once(std::string("drom ") + sub->name + ": error: " + e.what() + "\n");
      return 2;
    } catch (const std::exception& e) {
      say_once(std::string("drom ") + sub->name + ": failed: " + e.what() + "\n");
      return 1;
    }
  }
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  // First, before any thread has an arena of its own: the station solves' large blocks are kept and
  // reused rather than mapped and faulted in again (support/heap_policy.hpp).
  drom::keep_freed_memory();
  CLI::App app{"drom: predicts and corrects the distortion of thin parts while they are machined"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("drom ") + drom::kVersion);

  Arguments args;
  Registered commands;
  for (const auto& sub : kSubcommands) {
    CLI::App* cmd = app.add_subcommand(sub.name, sub.help);
    sub.add(*cmd, args);
    if (CLI::Option* out = cmd->get_option_no_throw("--out")) out->default_str(sub.out);
    commands.emplace_back(cmd, &sub);
  }
  if (const auto exit_code = parse(app, argc, argv)) return *exit_code;
  if (!args.case_path.empty()) args.options.case_path = args.case_path;
  return run_parsed(commands, args.options);
}
