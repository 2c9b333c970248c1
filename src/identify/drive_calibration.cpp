// Calibrating a robot's drives from a measured log (identify/drive_calibration.hpp).
#include "jointsim/identify/drive_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/control/trajectory.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/io/input_files.hpp"
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
  io::checkedTimes(t, tc, o.gap_factor);
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
    for (int j = 0; j < dof; ++j) {
      const auto J = static_cast<size_t>(j);
      log.q(k, j) = t.data(rows[static_cast<size_t>(k)], cq[J]);
      log.qd(k, j) = t.data(rows[static_cast<size_t>(k)], cqd[J]);
      log.qdd(k, j) = t.data(rows[static_cast<size_t>(k)], cqdd[J]);
      log.current(k, j) = t.data(rows[static_cast<size_t>(k)], ci[J]);
    }
  return log;
}

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
  const Eigen::MatrixXd pred = predictCurrents(model, cal.nominal, log, cal.fit);
  for (Eigen::Index j = 0; j < model.nq; ++j) {
    const Eigen::VectorXd m = log.current.col(j);
    const double R = m.maxCoeff() - m.minCoeff();
    const double rms = std::sqrt((pred.col(j) - m).squaredNorm() / static_cast<double>(m.size()));
    cal.rms_percent.push_back(R > 0.0 ? 100.0 * rms / R : 0.0);
  }

  // The drives file: the robot file's YAML with the calibrated motor constants and friction.
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
     << " samples\n# Per joint: k_t scale s, F_c+/- [N·m], F_v+/- [N·m·s/rad], inner-model RMS [% of range]:\n";
  for (size_t j = 0; j < cal.joints.size(); ++j) {
    const JointCurrentFit& f = cal.fit.joints[j];
    os << "#   " << cal.joints[j] << ": s " << calNum(f.kt_scale.value) << ", F_c " << calNum(f.coulomb_pos.value)
       << "/" << calNum(f.coulomb_neg.value) << ", F_v " << calNum(f.viscous_pos.value) << "/"
       << calNum(f.viscous_neg.value)
       << (o.fit.fit_offset ? ", current offset (not written) " + calNum(f.offset.value) + " A" : "") << ", RMS "
       << calNum(cal.rms_percent[j]) << " %\n";
  }
  os << e.c_str() << "\n";
  cal.drives_yaml = os.str();
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
  }
  return j.dump(2) + "\n";
}

}  // namespace jointsim::identify
