// Calibrating a robot's drives from a measured log (identify/drive_calibration.hpp).
#include "jointsim/identify/drive_calibration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/control/trajectory.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/sim/simulate.hpp"
#include "jointsim/systems/robot_with_drives.hpp"

namespace jointsim::identify {
namespace {

namespace fs = std::filesystem;

std::string calNum(double v) { return formatNumber(v, 6); }

/// A number as a YAML scalar with 8 significant digits (plain, not quoted).
std::string yamlNum(double v) { return formatNumber(v, 8); }

double tableValue(const std::vector<drive::ParameterInfo>& table, const std::string& key, double fallback) {
  for (const auto& p : table)
    if (p.key == key) return p.value;
  return fallback;
}

}  // namespace

CurrentLogColumns CurrentLogColumns::urRtde() {
  CurrentLogColumns c;
  c.time = "timestamp";
  c.q = "actual_q_{i}";
  c.qd = "target_qd_{i}";
  c.qdd = "target_qdd_{i}";
  c.current = "actual_current_{i}";
  return c;
}

CurrentLog readCurrentLog(const std::string& log_csv, int dof, const CurrentLogColumns& columns,
                          const DriveCalibrationOptions& o) {
  if (!(o.gap_factor == 0.0 || (o.gap_factor > 1.0 && std::isfinite(o.gap_factor))))
    throw InputError(log_csv + ": gap_factor must be > 1 (or 0 to disable the gap check), got " + calNum(o.gap_factor));
  const io::CsvTable t = io::readCsv(log_csv);
  const int tc = columns.time.empty() ? 0 : t.require(columns.time, "the log's time in s");
  auto cols = [&](const std::string& pattern, const char* key, const char* what) {
    std::vector<int> idx;
    for (const auto& n : control::LogColumns::expand(pattern, dof, key)) idx.push_back(t.require(n, what));
    return idx;
  };
  const auto cq = cols(columns.q, "q", "measured positions in rad"),
             cqd = cols(columns.qd, "qd", "velocities in rad/s"),
             cqdd = cols(columns.qdd, "qdd", "accelerations in rad/s^2"),
             ci = cols(columns.current, "current", "measured currents in A");
  const std::vector<double> times = io::checkedTimes(t, tc, o.gap_factor);
  std::vector<Eigen::Index> rows;
  for (Eigen::Index r = 0; r < t.rows(); ++r)
    if (t.data(r, tc) >= o.t_begin && t.data(r, tc) <= o.t_end) rows.push_back(r);
  if (rows.size() < 2)
    throw InputError(log_csv + ": no samples between " + calNum(o.t_begin) + " and " + calNum(o.t_end) + " s");
  CurrentLog log;
  log.source = log_csv;
  const auto K = static_cast<Eigen::Index>(rows.size());
  for (Eigen::MatrixXd* m : {&log.q, &log.qd, &log.qdd, &log.current}) m->resize(K, dof);
  for (Eigen::Index k = 0; k < K; ++k)
    log.t.push_back(times[static_cast<size_t>(rows[static_cast<size_t>(k)])] - times.front());
  for (Eigen::Index k = 0; k < K; ++k)
    for (int j = 0; j < dof; ++j) {
      const auto J = static_cast<size_t>(j);
      log.q(k, j) = t.data(rows[static_cast<size_t>(k)], cq[J]);
      log.qd(k, j) = t.data(rows[static_cast<size_t>(k)], cqd[J]);
      log.qdd(k, j) = t.data(rows[static_cast<size_t>(k)], cqdd[J]);
      log.current(k, j) = t.data(rows[static_cast<size_t>(k)], ci[J]);
    }
  return log;
}

namespace {

/// The inner model's RMS against the measured currents over every sample of `log`, per joint, % of range.
std::vector<double> rmsPercentOf(const multibody::Model& model, const std::vector<DriveNominal>& nominal,
                                 const CurrentLog& log, const CurrentFit& fit) {
  const Eigen::MatrixXd pred = predictCurrents(model, nominal, log, fit);
  std::vector<double> out;
  for (Eigen::Index j = 0; j < model.nq; ++j) {
    const Eigen::VectorXd m = log.current.col(j);
    const double R = m.maxCoeff() - m.minCoeff();
    const double rms = std::sqrt((pred.col(j) - m).squaredNorm() / static_cast<double>(m.size()));
    out.push_back(R > 0.0 ? 100.0 * rms / R : 0.0);
  }
  return out;
}

/// The drives file: the robot file's YAML with the calibrated motor constants and friction.
std::string renderDrives(const std::string& robot_file, const std::string& log_csv, const systems::RobotSystem& robot,
                         const DriveCalibration& cal, const DriveCalibrationOptions& o,
                         const std::string& output_file) {
  YAML::Node root = YAML::Load(io::readInputFile(robot_file, "robot-with-drives file"));
  const fs::path base = fs::absolute(robot_file).parent_path();
  const fs::path out_dir = fs::absolute(output_file).parent_path();
  const fs::path multibody = fs::absolute(base / root["multibody"].as<std::string>()).lexically_normal();
  root["multibody"] = fs::relative(multibody, out_dir).generic_string();
  YAML::Node drives = root["drives"];
  for (size_t k = 0; k < drives.size(); ++k) {
    YAML::Node d = drives[k];
    const std::string joint = d["joint"].as<std::string>();
    const auto it = std::find(cal.joints.begin(), cal.joints.end(), joint);
    if (it == cal.joints.end()) continue;
    const auto j = static_cast<size_t>(it - cal.joints.begin());
    const JointCurrentFit& f = cal.fit.joints[j];
    const systems::DriveSpec& spec = robot.drives()[j];
    const double kt = spec.motor.kt * f.kt_scale.value;
    YAML::Node motor = d["motor"];
    motor.SetStyle(YAML::EmitterStyle::Flow);
    motor["kt"] = yamlNum(kt);
    motor["ke"] = yamlNum(kt);
    const auto table =
        spec.friction ? systems::driveParameterTable(spec, "friction") : std::vector<drive::ParameterInfo>{};
    YAML::Node fr;
    fr["type"] = "lugre";
    fr["sigma0"] = yamlNum(tableValue(table, "sigma0", 1e5));
    fr["sigma1"] = yamlNum(tableValue(table, "sigma1", 300.0));
    auto branch = [](double fc, double fv) {
      YAML::Node b;
      b.SetStyle(YAML::EmitterStyle::Flow);
      b["alpha0"] = yamlNum(std::max(fc, 1e-6));  // LuGre needs α0 > 0
      b["alpha1"] = 0;
      b["alpha2"] = yamlNum(fv);
      b["v_s"] = yamlNum(0.1);
      return b;
    };
    fr["positive"] = branch(f.coulomb_pos.value, f.viscous_pos.value);
    fr["negative"] = branch(f.coulomb_neg.value, f.viscous_neg.value);
    d["friction"] = fr;
  }
  YAML::Emitter e;
  e << root;
  std::ostringstream os;
  os << "# Drives calibrated from a measured log by `jointsim identify currents` (docs/replay.md).\n"
     << "# Base file: " << fs::relative(fs::absolute(robot_file), out_dir).generic_string() << "\n"
     << "# Log: " << fs::relative(fs::absolute(log_csv), out_dir).generic_string() << ", " << cal.samples
     << " samples\n# Per joint" << (cal.refinement.kt_factor.empty() ? "" : " (the refined values)")
     << ": k_t scale s, F_c+/- [N·m], F_v+/- [N·m·s/rad], inner-model RMS [% of range]:\n";
  for (size_t j = 0; j < cal.joints.size(); ++j) {
    const JointCurrentFit& f = cal.fit.joints[j];
    os << "#   " << cal.joints[j] << ": s " << calNum(f.kt_scale.value) << ", F_c " << calNum(f.coulomb_pos.value)
       << "/" << calNum(f.coulomb_neg.value) << ", F_v " << calNum(f.viscous_pos.value) << "/"
       << calNum(f.viscous_neg.value)
       << (o.fit.fit_offset ? ", current offset (not written) " + calNum(f.offset.value) + " A" : "") << ", RMS "
       << calNum(cal.rms_percent[j]) << " %\n";
  }
  if (!cal.refinement.kt_factor.empty()) {
    os << "# Refined against the full twin replaying the log (" << cal.refinement.replays
       << " replays); the twin's RMS [% of range] before -> after:\n";
    for (size_t j = 0; j < cal.joints.size(); ++j)
      os << "#   " << cal.joints[j] << ": " << calNum(cal.refinement.rms_before[j]) << " -> "
         << calNum(cal.refinement.rms_after[j]) << " %\n";
  }
  os << e.c_str() << "\n";
  return os.str();
}

/// A unique scratch folder, removed with its content when the object goes.
struct ScratchDir {
  fs::path path;
  ScratchDir() {
    std::random_device rd;
    std::error_code ec;
    const fs::path tmp = fs::temp_directory_path(ec);
    for (int attempt = 0; attempt < 100 && path.empty() && !ec; ++attempt) {
      const fs::path p = tmp / ("jointsim-refine-" + std::to_string(rd()) + std::to_string(rd()));
      if (fs::create_directory(p, ec)) path = p;
    }
    if (path.empty()) throw InputError("cannot create a scratch folder under " + tmp.string() + ": " + ec.message());
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
};

/// See DriveCalibrationOptions::refine_experiment. Parameters per joint p = (a, c, v): factors on the inner fit's
/// k_t scale, Coulomb and viscous friction. Residuals: the replayed twin's current minus the measured one at the
/// measured samples of the window (the replay's t = 0 is the log's first sample).
TwinRefinement refineWithTwin(const std::string& robot_file, const std::string& log_csv, const CurrentLog& log,
                              const systems::RobotSystem& robot, const DriveCalibration& cal,
                              const DriveCalibrationOptions& o, const std::string& output_file) {
  (void)output_file;
  if (o.refine_iterations < 1)
    throw InputError("refine_iterations: expected >= 1, got " + std::to_string(o.refine_iterations));
  const int n = robot.model().nq;
  CurrentLog meas = log;       // the window's measured currents and times
  for (int j = 0; j < n; ++j)  // a fitted current offset belongs to the sensor: the twin has none
    meas.current.col(j).array() -= cal.fit.joints[static_cast<size_t>(j)].offset.value;
  const ScratchDir scratch;
  const std::string drives_file = (scratch.path / "drives.yaml").string();
  {
    std::ofstream out(drives_file);
    out << renderDrives(robot_file, log_csv, robot, cal, o, drives_file);
    out.close();
    if (!out) throw InputError("cannot write " + drives_file);
  }
  TwinRefinement r;
  r.kt_factor.assign(static_cast<size_t>(n), 1.0);
  r.coulomb_factor.assign(static_cast<size_t>(n), 1.0);
  r.viscous_factor.assign(static_cast<size_t>(n), 1.0);
  // Factors per joint: k_t, Coulomb +, Coulomb −, viscous +, viscous − (a joint moved one way only: one law).
  constexpr size_t M = 5;
  using P = std::array<double, M>;
  std::vector<P> p(static_cast<size_t>(n)), lo(static_cast<size_t>(n)), hi(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j) {
    const double s = cal.fit.joints[static_cast<size_t>(j)].kt_scale.value;
    p[static_cast<size_t>(j)].fill(1.0);
    // Friction factors >= 0.1: a LuGre friction with a vanishing Coulomb level is a degenerate, very stiff model.
    lo[static_cast<size_t>(j)] = {(1.0 - o.fit.scale_bound) / s, 0.1, 0.1, 0.1, 0.1};
    hi[static_cast<size_t>(j)] = {(1.0 + o.fit.scale_bound) / s, 5.0, 5.0, 5.0, 5.0};
  }
  // One law for both directions where the inner fit has one: a joint moved one way, or a symmetric Coulomb
  // friction with a current offset (fit_offset).
  auto oneLaw = [&](int j) { return cal.fit.joints[static_cast<size_t>(j)].tied || o.fit.fit_offset; };
  auto tie = [&](std::vector<P>& q) {
    for (int j = 0; j < n; ++j)
      if (oneLaw(j)) {
        q[static_cast<size_t>(j)][2] = q[static_cast<size_t>(j)][1];
        q[static_cast<size_t>(j)][4] = q[static_cast<size_t>(j)][3];
      }
  };
  // One replay with the factors q: the residuals per joint (measured samples of the window); none when the replay
  // fails (a trial's parameters that make the twin fail or exceed the step budget: ten times the first replay's).
  long budget = 0;
  auto replay = [&](const std::vector<P>& q) -> std::optional<Eigen::MatrixXd> {
    std::vector<std::string> over = o.refine_overrides;
    if (budget > 0) over.push_back("+limits.steps=" + std::to_string(budget));
    over.push_back("robot=" + drives_file);
    for (int j = 0; j < n; ++j) {
      const JointCurrentFit& f = cal.fit.joints[static_cast<size_t>(j)];
      const std::string key = "+drives." + cal.joints[static_cast<size_t>(j)] + ".";
      const P& x = q[static_cast<size_t>(j)];
      const double kt = robot.drives()[static_cast<size_t>(j)].motor.kt * f.kt_scale.value * x[0];
      over.push_back(key + "motor.kt=" + formatNumber(kt, 17));
      over.push_back(key + "motor.ke=" + formatNumber(kt, 17));
      over.push_back(key + "friction.positive.alpha0=" + formatNumber(std::max(f.coulomb_pos.value * x[1], 1e-6), 17));
      over.push_back(key + "friction.negative.alpha0=" + formatNumber(std::max(f.coulomb_neg.value * x[2], 1e-6), 17));
      over.push_back(key + "friction.positive.alpha2=" + formatNumber(f.viscous_pos.value * x[3], 17));
      over.push_back(key + "friction.negative.alpha2=" + formatNumber(f.viscous_neg.value * x[4], 17));
    }
    ++r.replays;
    const auto e = experiments::loadExperiment(o.refine_experiment, over);
    experiments::ExperimentResult res;
    try {
      res = experiments::runInMemory(*e);
    } catch (const sim::Interrupted&) {
      throw;  // a stop request ends the calibration, nothing is written
    } catch (const SolverError&) {
      if (budget == 0) throw;  // the calibrated drives themselves: an error to report
      return std::nullopt;
    }
    if (budget == 0) budget = std::max(10L * static_cast<long>(res.result.stats.steps), 1000000L);
    const sim::SignalTable& L = res.log;
    if (L.values.rows() < 2 || L.values(L.values.rows() - 1, 0) < meas.t.back() - 1e-9)
      throw InputError(o.refine_experiment + ": the replay ends at " +
                       formatNumber(L.values.rows() > 0 ? L.values(L.values.rows() - 1, 0) : 0.0) +
                       " s, before the log's window (" + formatNumber(meas.t.back()) +
                       " s after its first sample): set its duration");
    Eigen::MatrixXd resid(static_cast<Eigen::Index>(meas.t.size()), n);
    for (int j = 0; j < n; ++j) {
      const int c = L.column("current_" + cal.joints[static_cast<size_t>(j)] + "[A]");
      Eigen::Index row = 0;
      for (size_t k = 0; k < meas.t.size(); ++k) {
        const double t = meas.t[k];
        while (row + 2 < L.values.rows() && L.values(row + 1, 0) <= t) ++row;
        const double t0 = L.values(row, 0), t1 = L.values(row + 1, 0);
        const double w = std::clamp((t - t0) / (t1 - t0), 0.0, 1.0);
        const double i = (1.0 - w) * L.values(row, c) + w * L.values(row + 1, c);
        resid(static_cast<Eigen::Index>(k), j) = i - meas.current(static_cast<Eigen::Index>(k), j);
      }
    }
    return resid;
  };
  auto rmsPercent = [&](const Eigen::MatrixXd& resid, int j) {
    const Eigen::VectorXd m = meas.current.col(j);
    const double R = m.maxCoeff() - m.minCoeff();
    const double rms = std::sqrt(resid.col(j).squaredNorm() / static_cast<double>(resid.rows()));
    return R > 0.0 ? 100.0 * rms / R : rms;
  };
  constexpr double kStep = 0.05;  // finite-difference step of the factors (wide: stick–slip makes the response rough)
  std::vector<double> lambda(static_cast<size_t>(n), 1e-2);
  Eigen::MatrixXd base = *replay(p);
  for (int j = 0; j < n; ++j) r.rms_before.push_back(rmsPercent(base, j));
  for (int it = 0; it < o.refine_iterations; ++it) {
    std::array<Eigen::MatrixXd, M> d;
    for (size_t m = 0; m < M; ++m) {  // every joint's factor m at once: the other joints' currents barely move
      if (m == 2 || m == 4) {         // a tied joint's negative factors follow the positive ones
        bool any_free = false;
        for (int j = 0; j < n; ++j) any_free = any_free || !oneLaw(j);
        if (!any_free) {
          d[m] = Eigen::MatrixXd::Zero(base.rows(), n);
          continue;
        }
      }
      std::vector<P> q = p;
      for (size_t j = 0; j < q.size(); ++j) {
        double step = kStep * std::max(q[j][m], 0.2);
        if (q[j][m] + step > hi[j][m]) step = -step;
        q[j][m] += step;
      }
      tie(q);
      const auto dm = replay(q);
      if (!dm) {  // no slope for this factor in this iteration
        d[m] = Eigen::MatrixXd::Zero(base.rows(), n);
        continue;
      }
      d[m] = *dm;
      for (size_t j = 0; j < q.size(); ++j)
        d[m].col(static_cast<Eigen::Index>(j)) =
            (d[m].col(static_cast<Eigen::Index>(j)) - base.col(static_cast<Eigen::Index>(j))) / (q[j][m] - p[j][m]);
    }
    std::vector<P> trial = p;
    for (int j = 0; j < n; ++j) {
      const auto J = static_cast<size_t>(j);
      const bool tied = oneLaw(j);
      Eigen::MatrixXd Jm(base.rows(), static_cast<Eigen::Index>(M));
      for (size_t m = 0; m < M; ++m)
        Jm.col(static_cast<Eigen::Index>(m)) =
            tied && (m == 2 || m == 4) ? Eigen::VectorXd::Zero(base.rows()) : Eigen::VectorXd(d[m].col(j));
      Eigen::MatrixXd A = Jm.transpose() * Jm;
      const Eigen::VectorXd g = -Jm.transpose() * base.col(j);
      for (Eigen::Index m = 0; m < A.rows(); ++m) A(m, m) = A(m, m) * (1.0 + lambda[J]) + 1e-12;
      const Eigen::VectorXd step = A.ldlt().solve(g);
      for (size_t m = 0; m < M; ++m)
        if (std::isfinite(step[static_cast<Eigen::Index>(m)]))
          trial[J][m] = std::clamp(p[J][m] + step[static_cast<Eigen::Index>(m)], lo[J][m], hi[J][m]);
    }
    tie(trial);
    const auto tr = replay(trial);
    const std::vector<P> previous = p;
    std::vector<char> moved(static_cast<size_t>(n), 0);
    for (int j = 0; j < n; ++j) {
      const auto J = static_cast<size_t>(j);
      if (tr && rmsPercent(*tr, j) < rmsPercent(base, j)) {
        p[J] = trial[J];
        moved[J] = 1;
      } else {
        lambda[J] *= 8.0;
      }
    }
    // The accepted steps together (the joints' currents interact a little): a joint that came out worse goes back
    // (and once more if any did); a replay that fails restores the previous factors.
    for (int pass = 0; pass < 2; ++pass) {
      if (std::none_of(moved.begin(), moved.end(), [](char m) { return m != 0; })) break;
      const auto b = replay(p);
      bool reverted = false;
      for (int j = 0; j < n; ++j) {
        const auto J = static_cast<size_t>(j);
        if (!moved[J]) continue;
        if (b && rmsPercent(*b, j) <= rmsPercent(base, j)) continue;
        p[J] = previous[J];
        moved[J] = 0;
        lambda[J] *= 8.0;
        reverted = true;
      }
      if (!reverted && b) {
        base = *b;
        break;
      }
      if (pass == 1 || !b) {  // give up this iteration's steps
        p = previous;
        std::fill(moved.begin(), moved.end(), 0);
      }
    }
    for (int j = 0; j < n; ++j)
      if (moved[static_cast<size_t>(j)])
        lambda[static_cast<size_t>(j)] = std::max(lambda[static_cast<size_t>(j)] / 3.0, 1e-6);
  }
  for (int j = 0; j < n; ++j) {
    const auto J = static_cast<size_t>(j);
    r.kt_factor[J] = p[J][0];
    r.coulomb_factor[J] = p[J][1];
    r.coulomb_neg_factor.push_back(p[J][2]);
    r.viscous_factor[J] = p[J][3];
    r.viscous_neg_factor.push_back(p[J][4]);
    r.rms_after.push_back(rmsPercent(base, j));
  }
  return r;
}

}  // namespace

DriveCalibration calibrateDrives(const std::string& robot_file, const std::string& log_csv,
                                 const CurrentLogColumns& columns, const DriveCalibrationOptions& o,
                                 const std::string& output_file) {
  const systems::RobotSystem robot = systems::loadRobotWithDrives(robot_file);
  const multibody::Model& model = robot.model();
  DriveCalibration cal;
  cal.joints = model.joint_names;
  for (const systems::DriveSpec& d : robot.drives())
    cal.nominal.push_back({d.transmission->ratio(), d.motor.kt, d.motor.J_M});
  const CurrentLog log = readCurrentLog(log_csv, model.nq, columns, o);
  cal.samples = static_cast<long>(log.q.rows());
  cal.fit = fitDriveCurrents(model, cal.nominal, log, o.fit);
  cal.rms_percent = rmsPercentOf(model, cal.nominal, log, cal.fit);

  cal.drives_yaml = renderDrives(robot_file, log_csv, robot, cal, o, output_file);
  if (!o.refine_experiment.empty()) {
    cal.refinement = refineWithTwin(robot_file, log_csv, log, robot, cal, o, output_file);
    for (size_t j = 0; j < cal.fit.joints.size(); ++j) {  // the refined values (the standard errors stay the fit's)
      JointCurrentFit& f = cal.fit.joints[j];
      f.kt_scale.value *= cal.refinement.kt_factor[j];
      f.coulomb_pos.value *= cal.refinement.coulomb_factor[j];
      f.coulomb_neg.value *= cal.refinement.coulomb_neg_factor[j];
      f.viscous_pos.value *= cal.refinement.viscous_factor[j];
      f.viscous_neg.value *= cal.refinement.viscous_neg_factor[j];
      // The bounds the refined scale ends on.
      auto& b = f.at_bound;
      b.erase(std::remove(b.begin(), b.end(), "kt_scale"), b.end());
      if (std::abs(std::abs(f.kt_scale.value - 1.0) - o.fit.scale_bound) < 1e-9) b.insert(b.begin(), "kt_scale");
    }
    cal.rms_percent = rmsPercentOf(model, cal.nominal, log, cal.fit);  // the inner model with the refined values
    cal.drives_yaml = renderDrives(robot_file, log_csv, robot, cal, o, output_file);
  }
  return cal;
}

std::string formatCalibration(const DriveCalibration& c) {
  std::ostringstream os;
  char line[512];
  std::snprintf(line, sizeof line, "%-22s %17s %17s %17s %17s %17s %15s %7s\n", "joint", "kt scale s", "F_c+ [N·m]",
                "F_c- [N·m]", "F_v+ [N·m·s/rad]", "F_v- [N·m·s/rad]", "offset [A]", "rms[%R]");
  os << line;
  auto pm = [](const ParameterEstimate& p) { return calNum(p.value) + " ± " + calNum(p.std_error); };
  for (size_t j = 0; j < c.joints.size(); ++j) {
    const JointCurrentFit& f = c.fit.joints[j];
    std::snprintf(line, sizeof line, "%-22s %17s %17s %17s %17s %17s %15s %7.2f", c.joints[j].c_str(),
                  pm(f.kt_scale).c_str(), pm(f.coulomb_pos).c_str(), pm(f.coulomb_neg).c_str(),
                  pm(f.viscous_pos).c_str(), pm(f.viscous_neg).c_str(), pm(f.offset).c_str(), c.rms_percent[j]);
    os << line;
    if (f.tied) os << "  one direction only: F_c-, F_v- = F_c+, F_v+";
    if (!f.at_bound.empty()) {
      os << "  on a bound:";
      for (const auto& b : f.at_bound) os << " " << b;
    }
    os << "\n";
  }
  os << c.samples << " log samples; rms: the inner model against the measured currents over all of them (rest "
     << "included), in % of each joint's measured range\n";
  const TwinRefinement& r = c.refinement;
  if (!r.kt_factor.empty()) {
    os << "refined against the full twin (" << r.replays << " replays; the values above are the refined ones, the "
       << "standard errors the inner fit's):\n";
    for (size_t j = 0; j < c.joints.size(); ++j) {
      std::snprintf(line, sizeof line,
                    "%-22s factors k_t %.4f, Coulomb %.4f/%.4f, viscous %.4f/%.4f; twin rms[%%R] %.2f -> %.2f\n",
                    c.joints[j].c_str(), r.kt_factor[j], r.coulomb_factor[j], r.coulomb_neg_factor[j],
                    r.viscous_factor[j], r.viscous_neg_factor[j], r.rms_before[j], r.rms_after[j]);
      os << line;
    }
  }
  return os.str();
}

std::string calibrationJson(const DriveCalibration& c) {
  nlohmann::ordered_json j;
  j["samples"] = c.samples;
  j["joints"] = nlohmann::ordered_json::array();
  auto est = [](const ParameterEstimate& p) {
    return nlohmann::ordered_json{{"value", p.value}, {"std_error", p.std_error}};
  };
  for (size_t k = 0; k < c.joints.size(); ++k) {
    const JointCurrentFit& f = c.fit.joints[k];
    j["joints"].push_back({{"joint", c.joints[k]},
                           {"kt_scale", est(f.kt_scale)},
                           {"coulomb_pos", est(f.coulomb_pos)},
                           {"coulomb_neg", est(f.coulomb_neg)},
                           {"viscous_pos", est(f.viscous_pos)},
                           {"viscous_neg", est(f.viscous_neg)},
                           {"offset", est(f.offset)},
                           {"points", f.points},
                           {"one_direction_only", f.tied},
                           {"rms_percent", c.rms_percent[k]},
                           {"at_bound", f.at_bound}});
    if (!c.refinement.kt_factor.empty())
      j["joints"].back()["refinement"] = {{"kt_factor", c.refinement.kt_factor[k]},
                                          {"coulomb_pos_factor", c.refinement.coulomb_factor[k]},
                                          {"coulomb_neg_factor", c.refinement.coulomb_neg_factor[k]},
                                          {"viscous_pos_factor", c.refinement.viscous_factor[k]},
                                          {"viscous_neg_factor", c.refinement.viscous_neg_factor[k]},
                                          {"twin_rms_percent_before", c.refinement.rms_before[k]},
                                          {"twin_rms_percent_after", c.refinement.rms_after[k]}};
  }
  if (!c.refinement.kt_factor.empty()) j["refinement_replays"] = c.refinement.replays;
  return j.dump(2) + "\n";
}

}  // namespace jointsim::identify
