// `jointsim identify currents ROBOT.yaml LOG.csv -o DRIVES.yaml`: calibrates the drives of a robot-with-drives file
// from a measured log's motion and motor currents (identify/drive_calibration.hpp; docs/replay.md) and writes the
// calibrated robot-with-drives file.
#include <cstdio>
#include <limits>
#include <memory>

#include "cli_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/identify/drive_calibration.hpp"
#include "jointsim/io/output.hpp"

namespace jointsim::cli {

void addIdentifyCurrentsCommand(CLI::App& identify) {
  struct Options {
    std::string robot, log, output, json, format;
    identify::CurrentLogColumns columns;  // its defaults: the shipped UR5 log's names
    identify::DriveCalibrationOptions cal;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = identify.add_subcommand(
      "currents", "Calibrate a robot's drives (torque-constant scale, Coulomb and viscous friction per direction) "
                  "from a measured log's motion and motor currents; writes a robot-with-drives file (docs/replay.md)");
  cmd->add_option("robot", opt->robot, "Robot-with-drives file (the nominal drives)")->required();
  cmd->add_option("log", opt->log, "Measured log (CSV)")->required();
  cmd->add_option("-o,--output", opt->output, "The calibrated robot-with-drives file to write")->required();
  cmd->add_option("--format", opt->format, "Column names of a UR RTDE log (actual_q_{i}, target_qd_{i}, ...)")
      ->check(CLI::IsMember({"ur_rtde"}));
  cmd->add_option("--time", opt->columns.time, "Time column (default: the first column)");
  cmd->add_option("--q", opt->columns.q, "Measured positions, a pattern with {j} (1..n) or {i} (default q_actual_{j})");
  cmd->add_option("--qd", opt->columns.qd, "Velocities (default qd_target_{j}: the controller's, noise-free)");
  cmd->add_option("--qdd", opt->columns.qdd, "Accelerations (default qdd_target_{j})");
  cmd->add_option("--current", opt->columns.current, "Measured motor currents (default i_actual_{j})");
  cmd->add_option("--from", opt->cal.t_begin, "Use samples from this log time [s]");
  cmd->add_option("--to", opt->cal.t_end, "... up to this log time [s]");
  cmd->add_option("--min-speed", opt->cal.fit.min_speed, "Samples slower than this are not fitted [rad/s] (0.01)");
  cmd->add_option("--scale-bound", opt->cal.fit.scale_bound, "|k_t scale - 1| <= this (default 0.4)");
  cmd->add_flag("--fit-offset", opt->cal.fit.fit_offset,
                "Fit a current offset and a symmetric Coulomb friction instead of one per direction");
  cmd->add_option("--refine", opt->cal.refine_experiment,
                  "Refine against the full twin: a tracking experiment replaying this log from its first sample "
                  "(e.g. config/experiments/ur5_measured_replay.yaml; its robot is replaced)");
  cmd->add_option("--refine-set", opt->cal.refine_overrides,
                  "Override of that experiment, key.path=value (repeatable)");
  cmd->add_option("--refine-iterations", opt->cal.refine_iterations, "Iterations of the refinement (default 5)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--json", opt->json, "Also write the estimates as JSON to this file");
  cmd->callback([opt] {
    identify::CurrentLogColumns c = opt->columns;
    if (opt->format == "ur_rtde") {
      c = identify::CurrentLogColumns::urRtde();
      if (!opt->columns.time.empty()) c.time = opt->columns.time;
    }
    const identify::DriveCalibration cal = identify::calibrateDrives(opt->robot, opt->log, c, opt->cal, opt->output);
    io::writeFileAtomically(opt->output, cal.drives_yaml);
    if (!opt->json.empty()) io::writeFileAtomically(opt->json, identify::calibrationJson(cal));
    std::fputs(identify::formatCalibration(cal).c_str(), stdout);
    std::printf("calibrated drives written to %s\n", opt->output.c_str());
  });
}

}  // namespace jointsim::cli
