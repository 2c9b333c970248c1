// `jointsim identify clamping DATA.csv [--gear-ratio N] [-o FILE]`: Algorithm II preprocessing of [KR300Thesis] and a
// Ceres fit of the 1-D transmission model (stiffness, backlash, Coulomb friction; motor side). Writes a YAML
// report (default: DATA with ".csv" replaced by "_clamping.yaml") and prints a short summary.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "cli_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/identify/clamping_fit.hpp"
#include "jointsim/io/output.hpp"

namespace jointsim::cli {

namespace {
std::string clampingDefaultOutput(const std::string& data) {
  const size_t slash = data.find_last_of('/');
  const size_t dot = data.find_last_of('.');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  const std::string stem = has_ext ? data.substr(0, dot) : data;
  return stem + "_clamping.yaml";
}
}  // namespace

void addIdentifyClampingCommand(CLI::App& identify) {
  struct Options {
    std::string data, output;
    double gear_ratio = 1.0;
    std::optional<double> fix_backlash;
    bool fit_viscous = false, fit_damping = false, validate = false;
    double rotor_inertia = 0.01, damping = 0.5;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd =
      identify.add_subcommand("clamping", "Identify stiffness, backlash and friction (motor side) from a clamping log "
                                          "([KR300Thesis, Algorithm II] + Ceres)");
  cmd->add_option("data", opt->data, "CSV with columns time[s], motor_angle[rad], motor_torque[N*m]")->required();
  cmd->add_option("--gear-ratio", opt->gear_ratio,
                  "The torque column is arm side (motor torque x N, as KUKA logs): divide it by N (default 1)");
  cmd->add_option("-o,--output", opt->output, "YAML report (default: DATA with .csv replaced by _clamping.yaml)");
  cmd->add_option("--fix-backlash", opt->fix_backlash,
                  "Hold the total backlash at B [rad] (when the curve never crosses zero torque)");
  cmd->add_flag("--fit-viscous", opt->fit_viscous, "Also fit a viscous friction coefficient [N*m*s/rad]");
  cmd->add_flag("--fit-damping", opt->fit_damping, "Also fit the transmission damper [N*m*s/rad]");
  cmd->add_flag("--validate", opt->validate,
                "Simulate the dynamic 1-D model driven by the measured torque and report the angle residual");
  cmd->add_option("--rotor-inertia", opt->rotor_inertia, "Rotor inertia for --validate [kg*m^2] (default 0.01)");
  cmd->add_option("--damping", opt->damping, "Transmission damper for --validate [N*m*s/rad] (default 0.5)");
  cmd->callback([opt] {
    if (!(opt->gear_ratio > 0.0) || !std::isfinite(opt->gear_ratio))
      throw InputError("--gear-ratio: expected a finite gear ratio > 0, got " + std::to_string(opt->gear_ratio));
    if (opt->fix_backlash && !(*opt->fix_backlash >= 0.0 && std::isfinite(*opt->fix_backlash)))
      throw InputError("--fix-backlash: expected a finite backlash >= 0 rad, got " +
                       std::to_string(*opt->fix_backlash));
    if (!(opt->rotor_inertia > 0.0) || !std::isfinite(opt->rotor_inertia))
      throw InputError("--rotor-inertia: expected a finite inertia > 0 kg*m^2, got " +
                       std::to_string(opt->rotor_inertia));
    if (!(opt->damping >= 0.0) || !std::isfinite(opt->damping))
      throw InputError("--damping: expected a finite damping >= 0 N*m*s/rad, got " + std::to_string(opt->damping));
    const auto start = std::chrono::steady_clock::now();
    const identify::ClampingData data = identify::readClampingCsv(opt->data, opt->gear_ratio);
    identify::ClampingFitOptions options;
    options.fixed_backlash = opt->fix_backlash;
    options.fit_viscous = opt->fit_viscous;
    options.fit_damping = opt->fit_damping;
    options.simulate_validation = opt->validate;
    options.rotor_inertia = opt->rotor_inertia;
    options.validation_damping = opt->damping;
    const identify::ClampingFitResult r = identify::identifyClamping(data, options);
    const std::string out = opt->output.empty() ? clampingDefaultOutput(opt->data) : opt->output;
    io::writeFileAtomically(out, identify::clampingReportYaml(r, opt->data, opt->gear_ratio));
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const auto& cv = r.curves;
    std::printf("%s: clamping identification (motor side, gear ratio %g)\n", opt->data.c_str(), opt->gear_ratio);
    std::printf("  stiffness %.6g +- %.2g N*m/rad   backlash %.6g +- %.2g rad%s   friction %.6g +- %.2g N*m\n",
                r.stiffness.value, r.stiffness.std_error, r.backlash.value, r.backlash.std_error,
                r.backlash.fitted ? "" : " (fixed)", r.friction.value, r.friction.std_error);
    if (r.viscous) std::printf("  viscous friction %.6g +- %.2g N*m*s/rad\n", r.viscous->value, r.viscous->std_error);
    if (r.damping) std::printf("  damping %.6g +- %.2g N*m*s/rad\n", r.damping->value, r.damping->std_error);
    std::printf("  Algorithm II estimates: stiffness %.4g N*m/rad, backlash %.4g rad, friction %.4g N*m\n",
                cv.stiffness, cv.backlash, cv.friction);
    std::printf("  half-cycles: %zu found, %d upper + %d lower used, %d rejected; %d points, rms residual %.3g N*m\n",
                cv.half_cycles.size(), cv.used_upper, cv.used_lower, cv.rejected, r.points, r.rms_residual);
    if (r.validation_angle_rms)
      std::printf("  validation (dynamic model driven by the measured torque): angle rms %.3g rad\n",
                  *r.validation_angle_rms);
    std::printf("  report: %s (%.3g s)\n", out.c_str(), wall);
  });
}

}  // namespace jointsim::cli
