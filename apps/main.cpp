// drom: distortion-aware machining of thin parts. See README.md and docs/.
#include "apps/commands.hpp"
#include "support/heap_policy.hpp"
#include "support/input_error.hpp"
#include "support/version.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <string>

namespace {

// A message in one write: under mpirun every rank may say it at once, and the launcher forwards
// each write whole (piecewise writes came out interleaved).
void say_once(const std::string& message) {
  std::fflush(stdout);
  std::fwrite(message.data(), 1, message.size(), stderr);
}

}  // namespace

int main(int argc, char** argv) {
  // First, before any thread has an arena of its own: the station solves' large blocks are kept and
  // reused rather than mapped and faulted in again (support/heap_policy.hpp).
  drom::keep_freed_memory();
  CLI::App app{"drom: predicts and corrects the distortion of thin parts while they are machined"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("drom ") + drom::kVersion);

  drom::app::CommandOptions options;
  std::string case_path;
  struct Sub {
    const char* name;
    const char* help;
    int (*run)(const drom::app::CommandOptions&);
  };
  const Sub subs[] = {
      {"run", "the closed loop on a case (default: the embedded flat-plate case): offline, model, truth, corrected machining", drom::app::run_command},
      {"study", "sweep one closed-loop parameter (noise, angle, refresh, calibration, desync, amplitude, seed) and tabulate the headline errors",
       drom::app::study_command},
      {"layer", "the FE core on uniform layer removal, against the closed form", drom::app::layer_command},
      {"removal", "compute the material each tool station removes, on the case's mesh", drom::app::removal_command},
      {"offline", "simulate the machining once per unit stress profile: the snapshot database (B1, B2)", drom::app::offline_command},
      {"truth", "simulate the machining for the case's own stress profile, with full fields", drom::app::truth_command},
      {"merge", "assemble database.h5 from the slices that drom offline / truth --stations a:b left in --out's checkpoint folder",
       drom::app::merge_command},
      {"reduce", "compress an offline database into the light model the online predictor loads", drom::app::reduce_command},
      {"deviation", "learn an unknown blank's deviation from laser profiles during the approach (seed chapter 2)", drom::app::deviation_command},
      {"copy", "copy a scanned part from its point cloud by 3+2 machining: normals, visibility, packets, roughing and finishing per packet, G-code",
       drom::app::copy_command},
      {"finish", "finishing paths on a free-form surface in the least time under a scallop bound (zoning, tool choice, 3-axis or 3+2)",
       drom::app::finish_command},
      {"orient", "collision-free 5-axis tool axis along fixed CL paths from repulsive fields (seed 000), proved by a clearance check and put on a machine",
       drom::app::orient_command},
      {"mesh", "mesh the case's part and write it with its clamps to VTK", drom::app::mesh_command},
      {"check", "validate a case file and print it with every override applied", drom::app::check_command},
      {"machine", "a program (G-code or CL data) on a machine: travel, singularities, the feed it really reaches, the limiting axes, the cycle time",
       drom::app::machine_command},
  };
  std::vector<std::pair<CLI::App*, const Sub*>> commands;
  for (const auto& sub : subs) {
    CLI::App* cmd = app.add_subcommand(sub.name, sub.help);
    const bool reduce = std::string(sub.name) == "reduce";
    if (std::string(sub.name) == "machine") {
      cmd->add_option("program", case_path, "G-code (.ngc, .nc, ...) or CL data (.apt, .cl, .cls, .csv)")->required();
      cmd->add_option("--machine", options.machine, "machine file (TOML), or a shipped machine: vmc_3axis, ucp710_like, gantry_head_ac")->capture_default_str();
      cmd->add_option("--set", options.overrides, "override a machine value, e.g. --set setup.tool_length=80 (repeatable)")->take_all();
      cmd->add_option("--reader", options.reader, "auto: drom's reader for the plain subset, LinuxCNC's rs274 otherwise")
          ->capture_default_str()
          ->check(CLI::IsMember({"auto", "plain", "rs274"}));
      cmd->add_option("--tool-diameter", options.tool_diameters, "T=D: tool T's diameter in mm, for cutter compensation (repeatable)")->take_all();
      cmd->add_option("--subroutine-path", options.subroutine_paths, "a folder rs274 searches for O<name> call (repeatable)")->take_all();
      cmd->add_option("--sample-period", options.sample_period, "seconds between rows of axes.csv (default: the interpolation cycle)")
          ->check(CLI::PositiveNumber);
    } else if (std::string(sub.name) == "copy") {
      cmd->add_option("cloud", case_path, "the scanned cloud: XYZ/CSV (x y z [nx ny nz]) or PLY (ascii or binary)")->required();
      cmd->add_option("--settings", options.settings, "settings file (TOML; docs/case-files.md, \"drom copy\"); default: the seed's hip run");
      cmd->add_option("--tool", options.tool, "finishing tool: ball:D, torus:D:r or flat:D (mm); default: the settings' (ball:6)");
      cmd->add_option("--machine", options.copy_machine, "machine file (TOML) or shipped machine; default: the settings' (ucp710_like)");
      cmd->add_option("--set", options.overrides, "override a setting, e.g. --set packets.coverage=0.9 (repeatable)")->take_all();
    } else if (reduce) {
      cmd->add_option("database", case_path, "database.h5 written by drom offline")->required();
      cmd->add_option("--tol", options.tolerance, "POD truncation: max-norm error bound, mm (seed eq. 2.9)")->capture_default_str()->check(CLI::PositiveNumber);
      cmd->add_option("--history-tol", options.history_tolerance, "space-time compression of all basis histories together, mm (default: --tol / 2)")
          ->check(CLI::PositiveNumber);
      cmd->add_option("--scale", options.profile_scale, "plausible amplitude per unit profile, MPa (default: the case's largest coefficient)")
          ->check(CLI::PositiveNumber);
      cmd->add_option("--max-rank", options.max_rank, "cap on the number of POD modes")->check(CLI::PositiveNumber);
      cmd->add_option("--prior-mean", options.prior_mean, "the prior's mean: the case's [stress] profile, or zero")
          ->capture_default_str()
          ->check(CLI::IsMember({"case", "zero"}));
      cmd->add_option("--top-margin", options.top_margin,
                      "also keep the stock's top within this many mm of the pocket (what the laser reads ahead of the cut and around the "
                      "pocket); default: the machined floor only")
          ->check(CLI::NonNegativeNumber);
    } else {
      cmd->add_option("case", case_path, "case file (TOML); see cases/ and docs/case-files.md");
      cmd->add_option("--set", options.overrides, "override a case value, e.g. --set mesh.nx=20 (repeatable)")->take_all();
    }
    if (std::string(sub.name) == "machine") options.out = "out/machine";
    if (std::string(sub.name) == "copy") options.out = "out/copy";
    cmd->add_option("--out", options.out, reduce ? "model file (.h5), or a folder for model.h5" : "output folder")->capture_default_str();
    cmd->add_flag("--quiet", options.quiet, "no progress or table, only files");
    if (std::string(sub.name) == "study") {
      cmd->add_option("--param", options.study_parameter, "the parameter: noise, angle, refresh, calibration, desync, amplitude or seed (the noise draw)")->required();
      cmd->add_option("--values", options.study_values, "its values, e.g. --values 0,0.02,0.05")->required()->delimiter(',');
    }
    if (std::string(sub.name) == "run") {
      cmd->add_flag("--replan", options.replan, "re-plan a finishing pass on the predicted final shape, sampled as a cloud, and report its distance to the truth");
      cmd->add_option("--threads", options.threads, "the offline-and-truth pass's worker threads, per rank (default: one per hardware thread)")
          ->check(CLI::PositiveNumber);
    }
    if (std::string(sub.name) == "finish")
      cmd->add_option("--threads", options.threads, "K values optimised at once (default: one per hardware thread)")->check(CLI::PositiveNumber);
    if (std::string(sub.name) == "orient")
      cmd->add_option("--threads", options.threads, "passes integrated and poses checked at once (default: one per hardware thread)")->check(CLI::PositiveNumber);
    if (std::string(sub.name) == "offline" || std::string(sub.name) == "truth") {
      cmd->add_flag("--resume", options.resume, "continue the interrupted run in --out (refuses a different case)");
      cmd->add_option("--stop-after", options.stop_after, "solve at most N stations in this invocation, then stop (resume later)")->check(CLI::NonNegativeNumber);
      cmd->add_option("--threads", options.threads, "worker threads (default: one per hardware thread)")->check(CLI::PositiveNumber);
      cmd->add_option("--frames", options.frames, "full-field VTK frames over the stations (default: 10 for truth, 0 for offline)")
          ->check(CLI::NonNegativeNumber);
      cmd->add_option("--stations", options.stations,
                      "only stations a to b - 1 (a:b, a: or :b), into --out's checkpoint folder; drom merge writes the database once all are there");
      cmd->add_option("--export-ccx", options.export_ccx,
                      "instead of the job: station K (0-based) as a CalculiX deck (station_K.inp, run ccx -i station_K) with drom's answer beside it "
                      "(station_K_drom.csv)")
          ->check(CLI::NonNegativeNumber);
    }
    if (std::string(sub.name) == "merge") {
      cmd->add_option("--kind", options.merge_kind, "the slices of drom offline or of drom truth")->capture_default_str()->check(CLI::IsMember({"offline", "truth"}));
      cmd->add_option("--threads", options.threads, "worker threads for the final shape (default: one per hardware thread)")->check(CLI::PositiveNumber);
      cmd->add_option("--frames", options.frames, "as the slices were run with (default: 10 for truth, 0 for offline)")->check(CLI::NonNegativeNumber);
    }
    commands.emplace_back(cmd, &sub);
  }

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
  if (!case_path.empty()) options.case_path = case_path;

  for (const auto& [cmd, sub] : commands) {
    if (!cmd->parsed()) continue;
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
