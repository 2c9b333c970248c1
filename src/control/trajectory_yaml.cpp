#include "jointsim/control/trajectory_yaml.hpp"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "jointsim/common/error.hpp"
#include "jointsim/control/kinematic_ptp.hpp"

namespace jointsim::control {

using io::YamlValue;

namespace {

std::string trajectoryYamlNum(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

Eigen::VectorXd positions(const YamlValue& node, int dof, const std::string& what) {
  const auto v = node.asDoubles(static_cast<size_t>(dof), "a list of " + std::to_string(dof) + " " + what);
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

double positive(const YamlValue& node, const std::string& what) {
  const double x = node.asDouble(what + " > 0");
  if (!(x > 0.0)) node.failExpected(what + " > 0");
  return x;
}

double nonNegative(const YamlValue& node, double fallback, const std::string& what) {
  if (!node.defined()) return fallback;
  const double x = node.asDouble(what + " >= 0");
  if (!(x >= 0.0)) node.failExpected(what + " >= 0");
  return x;
}

std::unique_ptr<JointTrajectory> readPointToPoint(const YamlValue& node, int dof) {
  node.allowKeys({"type", "start", "segments"});
  const Eigen::VectorXd start =
      positions(node.required("start", "start joint positions in rad"), dof, "joint positions in rad");
  const YamlValue segs = node.required("segments", "a list of moves {target, velocity, acceleration, dwell}");
  segs.expectSequence("a list of moves {target, velocity, acceleration, dwell}");
  if (segs.size() == 0) segs.failExpected("at least one move");
  std::vector<PtpSegment> out;
  Eigen::VectorXd from = start;
  for (size_t k = 0; k < segs.size(); ++k) {
    const YamlValue s = segs.at(k);
    s.expectMap("a move {target, velocity, acceleration, dwell} or {target, duration, dwell}");
    s.allowKeys({"target", "velocity", "acceleration", "duration", "dwell"});
    PtpSegment g;
    g.target = positions(s.required("target", "joint positions in rad"), dof, "joint positions in rad");
    g.dwell = nonNegative(s["dwell"], 0.0, "a dwell time in s");
    if (s.has("duration")) {
      if (s.has("velocity")) s["velocity"].fail("give either velocity (with acceleration) or duration, not both");
      g.duration = positive(s["duration"], "a move time in s");
      if (s.has("acceleration")) {
        g.acceleration = positive(s["acceleration"], "a joint acceleration in rad/s^2");
        const double D = (g.target - from).cwiseAbs().maxCoeff(), T = g.duration;
        if (g.acceleration < 4.0 * D / (T * T))
          s["acceleration"].fail("acceleration " + trajectoryYamlNum(g.acceleration) + " rad/s^2 is too low to move " +
                                 trajectoryYamlNum(D) + " rad in " + trajectoryYamlNum(T) +
                                 " s (needs at least 4 D / T^2 = " + trajectoryYamlNum(4.0 * D / (T * T)) +
                                 " rad/s^2)");
      }
    } else {
      g.velocity =
          positive(s.required("velocity", "max joint speed in rad/s, or give duration"), "a joint speed in rad/s");
      g.acceleration =
          positive(s.required("acceleration", "max joint acceleration in rad/s^2"), "a joint acceleration in rad/s^2");
    }
    from = g.target;
    out.push_back(std::move(g));
  }
  return std::make_unique<PointToPointTrajectory>(start, std::move(out));
}

Eigen::MatrixXd coefficients(const YamlValue& node, int dof, long& harmonics) {
  const std::string what = "a list of " + std::to_string(dof) + " rows (one per joint) of coefficients in rad/s";
  node.expectSequence(what);
  if (node.size() != static_cast<size_t>(dof)) node.failExpected(what);
  Eigen::MatrixXd m;
  for (size_t i = 0; i < node.size(); ++i) {
    const YamlValue row = node.at(i);
    if (harmonics <= 0) {
      row.expectSequence("a list of coefficients in rad/s (one per harmonic)");
      if (row.size() == 0) row.failExpected("at least one coefficient in rad/s");
      harmonics = static_cast<long>(row.size());
    }
    const auto v = row.asDoubles(static_cast<size_t>(harmonics), "a list of " + std::to_string(harmonics) +
                                                                     " coefficients in rad/s (one per harmonic)");
    if (m.size() == 0) m.resize(dof, harmonics);
    for (long k = 0; k < harmonics; ++k) m(static_cast<Eigen::Index>(i), k) = v[static_cast<size_t>(k)];
  }
  return m;
}

std::unique_ptr<JointTrajectory> readFourier(const YamlValue& node, int dof) {
  node.allowKeys({"type", "base_frequency", "harmonics", "offset", "a", "b", "fade_in", "duration"});
  FourierParams p;
  p.base_frequency = positive(node.required("base_frequency", "f_base in Hz"), "a frequency in Hz");
  long n_harm = 0;
  if (node.has("harmonics")) {
    n_harm = node["harmonics"].asInt("a number of harmonics >= 1");
    if (n_harm < 1) node["harmonics"].failExpected("a number of harmonics >= 1");
  }
  p.offset = positions(node.required("offset", "q0 in rad"), dof, "joint positions in rad");
  p.a = coefficients(node.required("a", "sine coefficients in rad/s, n rows of N"), dof, n_harm);
  p.b = coefficients(node.required("b", "cosine coefficients in rad/s, n rows of N"), dof, n_harm);
  p.fade_in = nonNegative(node["fade_in"], 1.0, "a fade-in time in s");
  if (node.has("duration")) {
    p.duration = positive(node["duration"], "a duration in s");
    if (p.duration < p.fade_in)
      node["duration"].failExpected("a duration >= fade_in (" + trajectoryYamlNum(p.fade_in) + " s)");
  }
  return std::make_unique<FourierTrajectory>(std::move(p));
}

std::unique_ptr<JointTrajectory> readCsv(const YamlValue& node, int dof, const std::string& base_dir) {
  node.allowKeys({"type", "file", "columns", "gap_factor"});
  const YamlValue file_node = node.required("file", "CSV file, relative to this file");
  std::filesystem::path file = file_node.asString("a file path");
  if (file.is_relative()) file = std::filesystem::path(base_dir) / file;
  std::vector<std::string> columns;
  if (node.has("columns")) {
    const YamlValue c = node["columns"];
    const std::string what = "a list of " + std::to_string(dof) + " column names (one per joint, in joint order)";
    c.expectSequence(what);
    if (c.size() != static_cast<size_t>(dof)) c.failExpected(what);
    for (size_t i = 0; i < c.size(); ++i) columns.push_back(c.at(i).asString("a column name"));
  }
  double gap_factor = 3.0;
  if (node.has("gap_factor")) {
    gap_factor = node["gap_factor"].asDouble("a factor > 1 (0 disables the gap check)");
    if (!(gap_factor == 0.0 || gap_factor > 1.0))
      node["gap_factor"].failExpected("a factor > 1 (0 disables the gap check)");
  }
  try {
    return std::make_unique<SampledTrajectory>(
        SampledTrajectory::fromCsv(file.lexically_normal().string(), dof, columns, gap_factor));
  } catch (const InputError& e) {
    file_node.fail(e.what());
  }
}

// type: kinematic_ptp — MSL KinematicPTP2 (kinematic_ptp.hpp). Keys as the MSL parameters, SI units:
// q_begin, q_end [rad], qd_max [rad/s] (> 0), qdd_max [rad/s^2] (> 0): lists of dof; start_time [s] >= 0,
// default 0.
std::unique_ptr<JointTrajectory> readKinematicPtp(const YamlValue& node, int dof) {
  node.allowKeys({"type", "q_begin", "q_end", "qd_max", "qdd_max", "start_time"});
  const Eigen::VectorXd qb =
      positions(node.required("q_begin", "start joint positions in rad"), dof, "joint positions in rad");
  const Eigen::VectorXd qe =
      positions(node.required("q_end", "end joint positions in rad"), dof, "joint positions in rad");
  const YamlValue vn = node.required("qd_max", "max joint speeds in rad/s");
  const Eigen::VectorXd v = positions(vn, dof, "max joint speeds in rad/s");
  if (!(v.array() > 0.0).all())
    vn.failExpected("a list of " + std::to_string(dof) + " max joint speeds in rad/s, each > 0");
  const YamlValue an = node.required("qdd_max", "max joint accelerations in rad/s^2");
  const Eigen::VectorXd a = positions(an, dof, "max joint accelerations in rad/s^2");
  if (!(a.array() > 0.0).all())
    an.failExpected("a list of " + std::to_string(dof) + " max joint accelerations in rad/s^2, each > 0");
  const double t0 = nonNegative(node["start_time"], 0.0, "a start time in s");
  return std::make_unique<KinematicPtpTrajectory>(qb, qe, v, a, t0);
}

// type: log — LoggedTrajectory (trajectory.hpp): a robot log's commanded q, qd (, qdd) by Hermite interpolation.
std::unique_ptr<JointTrajectory> readLog(const YamlValue& node, int dof, const std::string& base_dir) {
  node.allowKeys({"type", "file", "format", "columns", "start_time", "gap_factor", "positions", "rest_speed"});
  const YamlValue file_node = node.required("file", "robot log CSV file, relative to this file");
  std::filesystem::path file = file_node.asString("a file path");
  if (file.is_relative()) file = std::filesystem::path(base_dir) / file;
  LogColumns cols;
  if (const YamlValue f = node["format"]; f.defined()) {
    const std::string name = f.asString("a log format (ur_rtde)");
    if (name != "ur_rtde") f.failExpected("a log format: ur_rtde (or name the columns under `columns`)");
    cols = LogColumns::urRtde(dof);
  }
  const std::string what = "a column-name pattern with {j} (joint 1..n) or {i} (index 0..n-1), or a list of " +
                           std::to_string(dof) + " column names";
  auto names = [&](const YamlValue& v) {
    if (v.isSequence()) {
      if (v.size() != static_cast<size_t>(dof)) v.failExpected(what);
      std::vector<std::string> out;
      for (size_t i = 0; i < v.size(); ++i) out.push_back(v.at(i).asString("a column name"));
      return out;
    }
    try {
      return LogColumns::expand(v.asString(what), dof, "columns");
    } catch (const InputError&) {
      v.failExpected(what);
    }
  };
  if (const YamlValue c = node["columns"]; c.defined()) {
    c.expectMap("a mapping {time, q, qd, qdd, q_measured} of column names");
    c.allowKeys({"time", "q", "qd", "qdd", "q_measured"});
    if (c.has("time")) cols.time = c["time"].asString("the time column's name");
    if (c.has("q")) cols.q = names(c["q"]);
    if (c.has("qd")) cols.qd = names(c["qd"]);
    // qdd and q_measured may be switched off with an empty list (e.g. under a preset).
    auto optional = [&](const YamlValue& v) {
      return v.isSequence() && v.size() == 0 ? std::vector<std::string>{} : names(v);
    };
    if (c.has("qdd")) cols.qdd = optional(c["qdd"]);
    if (c.has("q_measured")) cols.q_measured = optional(c["q_measured"]);
  }
  if (cols.q.empty()) node["columns"].fail("name the commanded positions: columns.q (or format: ur_rtde)");
  if (cols.qd.empty()) node["columns"].fail("name the commanded velocities: columns.qd (or format: ur_rtde)");
  double start = -1.0;
  if (node.has("start_time")) {
    start = node["start_time"].asDouble("the log time that becomes t = 0, in s");
    if (!std::isfinite(start)) node["start_time"].failExpected("a finite time in s");
  }
  double gap_factor = 3.0;
  if (node.has("gap_factor")) {
    gap_factor = node["gap_factor"].asDouble("a factor > 1 (0 disables the gap check)");
    if (!(gap_factor == 0.0 || gap_factor > 1.0))
      node["gap_factor"].failExpected("a factor > 1 (0 disables the gap check)");
  }
  bool from_derivatives = true;
  if (const YamlValue pos = node["positions"]; pos.defined()) {
    const std::string v = pos.asString("derivatives or logged");
    if (v != "derivatives" && v != "logged")
      pos.failExpected("derivatives (integrated from the logged qd, qdd; a held position per rest) or logged");
    from_derivatives = v == "derivatives";
  }
  double rest_speed = LoggedTrajectory::kRestSpeed;
  if (node.has("rest_speed")) {
    rest_speed = node["rest_speed"].asDouble("a speed in rad/s");
    if (!(rest_speed >= 0.0) || !std::isfinite(rest_speed))
      node["rest_speed"].failExpected("a speed >= 0 rad/s (below it a logged sample counts as a rest)");
  }
  try {
    return std::make_unique<LoggedTrajectory>(LoggedTrajectory::fromCsv(
        file.lexically_normal().string(), dof, cols, start, gap_factor, from_derivatives, rest_speed));
  } catch (const InputError& e) {
    (node.has("start_time") && std::string(e.what()).find("start time") != std::string::npos ? node["start_time"]
                                                                                             : file_node)
        .fail(e.what());
  }
}

}  // namespace

std::unique_ptr<JointTrajectory> trajectoryFromYaml(const YamlValue& node, int dof, const std::string& base_dir) {
  if (dof < 1) throw InputError("trajectoryFromYaml: dof must be >= 1");
  node.expectMap("a trajectory mapping {type: point_to_point|fourier|csv|log|kinematic_ptp, ...}");
  const YamlValue type = node.required("type", "point_to_point, fourier, csv, log or kinematic_ptp");
  const std::string t = type.asString("a trajectory type");
  try {
    if (t == "point_to_point") return readPointToPoint(node, dof);
    if (t == "fourier") return readFourier(node, dof);
    if (t == "csv") return readCsv(node, dof, base_dir);
    if (t == "kinematic_ptp") return readKinematicPtp(node, dof);
    if (t == "log") return readLog(node, dof, base_dir);
  } catch (const InputError& e) {
    node.relocate(e);
  }
  type.failExpected("a trajectory type (point_to_point, fourier, csv, log, kinematic_ptp)");
}

}  // namespace jointsim::control
