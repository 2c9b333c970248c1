// `jointsim identify friction MAP.csv [-o FILE]`: fits the static friction map ([Hauschild2003, eqs. 4.6, 4.21]) per
// direction with Ceres (jointsim::identify::fitFrictionMap) and writes a friction YAML block plus the fit
// statistics. Default output: MAP with ".csv" replaced by "_friction.yaml"; "-o -" writes to stdout.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "cli_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/identify/friction_fit.hpp"
#include "jointsim/io/output.hpp"

namespace jointsim::cli {

namespace {
struct FrictionOptions {
  std::string map, output, lugre, loss = "none";
  double delta = 2.0;
  bool fit_delta = false;
  int min_points = 8;
  double loss_scale = 0.1;
  double k_s = 300.0;
};

std::string frictionDefaultOutput(const std::string& map) {
  const std::string ext = ".csv";
  const bool has_ext = map.size() > ext.size() && map.compare(map.size() - ext.size(), ext.size(), ext) == 0;
  return (has_ext ? map.substr(0, map.size() - ext.size()) : map) + "_friction.yaml";
}

void printDirection(const identify::DirectionFit& d) {
  std::printf("  %s (%d points, |v| %.3g..%.3g rad/s, rms residual %.4g N·m):\n", d.direction.c_str(), d.points,
              d.min_speed, d.max_speed, d.rms_residual);
  std::printf("    alpha0 = %.6g ± %.2g N·m\n    alpha1 = %.6g ± %.2g N·m\n    alpha2 = %.6g ± %.2g N·m·s/rad\n"
              "    v_s    = %.6g ± %.2g rad/s\n",
              d.alpha0.value, d.alpha0.std_error, d.alpha1.value, d.alpha1.std_error, d.alpha2.value,
              d.alpha2.std_error, d.v_s.value, d.v_s.std_error);
}
}  // namespace

void addIdentifyFrictionCommand(CLI::App& identify) {
  auto opt = std::make_shared<FrictionOptions>();
  CLI::App* cmd = identify.add_subcommand(
      "friction", "Fit the static friction map F(v) = (a0 + a1 exp(-(|v|/v_s)^delta)) sgn(v) + a2 v per direction "
                  "([Hauschild2003, eq. 4.6] / LuGre eq. 4.21); writes a friction YAML block with standard errors");
  cmd->add_option("map", opt->map, "CSV with columns velocity[rad/s], friction_torque[N*m]")->required();
  cmd->add_option("-o,--output", opt->output,
                  "Output YAML file (default: MAP without .csv + _friction.yaml; - = stdout)");
  cmd->add_option("--lugre", opt->lugre,
                  "Write a `type: lugre` block with the given dynamic parameters SIGMA0,SIGMA1 [N·m/rad, N·m·s/rad] "
                  "(a static map cannot determine them; [Hauschild2003] used 259,10)");
  cmd->add_option("--delta", opt->delta,
                  "Stribeck form factor delta [-] (default 2 = LuGre; start value with --fit-delta)");
  cmd->add_flag("--fit-delta", opt->fit_delta, "Fit one delta shared by both directions (stribeck output only)");
  cmd->add_option("--min-points", opt->min_points, "Minimum number of points per direction (default 8)");
  cmd->add_option("--loss", opt->loss, "Robust loss on the torque residuals (default none)")
      ->check(CLI::IsMember({"none", "huber", "cauchy"}));
  cmd->add_option("--loss-scale", opt->loss_scale, "Residual scale of the robust loss [N·m] (default 0.1)");
  cmd->add_option("--k-s", opt->k_s,
                  "Slope-limiter factor k_s written to a stribeck block [s/rad] "
                  "(default 300, [Hauschild2003, eq. 4.24])");
  cmd->callback([opt] {
    const auto t0 = std::chrono::steady_clock::now();
    identify::FrictionFitOptions fo;
    fo.delta = opt->delta;
    fo.fit_delta = opt->fit_delta;
    fo.min_points = opt->min_points;
    fo.loss = opt->loss == "huber"    ? identify::FitLoss::Huber
              : opt->loss == "cauchy" ? identify::FitLoss::Cauchy
                                      : identify::FitLoss::None;
    fo.loss_scale = opt->loss_scale;
    identify::FrictionYamlOptions yo;
    yo.source = opt->map;
    yo.k_s = opt->k_s;
    if (!opt->lugre.empty()) {
      const Eigen::VectorXd s = parseList(opt->lugre, "--lugre", 2, "SIGMA0 [N·m/rad],SIGMA1 [N·m·s/rad]");
      yo.lugre = true;
      yo.sigma0 = s[0];
      yo.sigma1 = s[1];
      if (opt->fit_delta)
        throw InputError("--lugre: the LuGre model has delta = 2; do not combine it with --fit-delta");
      if (opt->delta != 2.0) throw InputError("--lugre: the LuGre model has delta = 2; do not combine it with --delta");
    }
    fo.validate();
    const identify::FrictionMapData data = identify::readFrictionMap(opt->map);
    const identify::FrictionFit fit = identify::fitFrictionMap(data.velocity, data.torque, fo);
    yo.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string yaml = identify::frictionFitYaml(fit, yo);
    if (opt->output == "-") {
      std::fputs(yaml.c_str(), stdout);
      return;
    }
    const std::string out = opt->output.empty() ? frictionDefaultOutput(opt->map) : opt->output;
    io::writeFileAtomically(out, yaml);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("friction map %s: %s block written to %s\n", opt->map.c_str(), yo.lugre ? "lugre" : "stribeck",
                out.c_str());
    if (fit.dropped_zero > 0) std::printf("  dropped %d points with v = 0 (neither direction)\n", fit.dropped_zero);
    std::printf("  delta = %.6g%s\n", fit.delta.value, fit.delta_fitted ? "" : " (fixed)");
    printDirection(fit.positive);
    printDirection(fit.negative);
    std::printf("  %d Ceres iterations, fit %.3g s, wall time %.3g s\n", fit.iterations, fit.solve_time_s, wall);
  });
}

}  // namespace jointsim::cli
