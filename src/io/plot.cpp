// `jointsim plot`: figures of a run folder or a sweep folder, drawn by gnuplot (pngcairo and svg terminals).
//
// The figures are described as data (Figure → Panel → Series, each series a gnuplot `using` clause on the run's
// CSV or on a small inline datablock), rendered into one gnuplot script per folder, and drawn by one gnuplot
// process. gnuplot writes every figure to a temporary name; they are renamed into place only when gnuplot has
// exited successfully, and removed otherwise.
#include "jointsim/io/plot.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <tuple>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "jointsim/common/error.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/io/output.hpp"

extern char** environ;

namespace jointsim::io {
namespace {
namespace fs = std::filesystem;

// ------------------------------------------------------------------------------------------------ text helpers

/// gnuplot single-quoted string literal (the only escape is '' for ').
std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += (c == '\'') ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string num(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", x);
  return buf;
}

std::string readTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool startsWith(const std::string& s, const std::string& prefix) { return s.compare(0, prefix.size(), prefix) == 0; }
bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// Splits a CSV header `name[unit]` at its last bracket pair ("w_a[1][rad/s]" -> "w_a[1]", "rad/s").
std::pair<std::string, std::string> splitHeader(const std::string& header) {
  if (!header.empty() && header.back() == ']') {
    const size_t open = header.rfind('[');
    if (open != std::string::npos && open > 0)
      return {header.substr(0, open), header.substr(open + 1, header.size() - open - 2)};
  }
  return {header, ""};
}

/// "quantity [unit]", or just the quantity for dimensionless ("-" or no unit) signals.
std::string label(const std::string& quantity, const std::string& unit) {
  return (unit.empty() || unit == "-" || unit == "1") ? quantity : quantity + " [" + unit + "]";
}

// ------------------------------------------------------------------------------------------------ summary.json

/// Just enough JSON to read scalars out of the summary.json written by io::JsonWriter: walks the object keys
/// along `path` and returns the scalar found there (a string unescaped, a number or literal as written).
class JsonPeek {
 public:
  explicit JsonPeek(std::string text) : s_(std::move(text)) {}

  std::optional<std::string> get(const std::vector<std::string>& path) {
    i_ = 0;
    try {
      return find(path, 0);
    } catch (const std::out_of_range&) {
      return std::nullopt;
    }
  }

 private:
  void ws() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  char peek() {
    ws();
    return s_.at(i_);
  }
  std::string string() {  // at the opening quote
    std::string out;
    ++i_;
    for (; s_.at(i_) != '"'; ++i_) {
      if (s_[i_] != '\\') {
        out += s_[i_];
        continue;
      }
      const char e = s_.at(++i_);
      out += e == 'n' ? '\n' : e == 't' ? '\t' : e == 'r' ? '\r' : e == 'b' ? '\b' : e == 'f' ? '\f' : e;
      if (e == 'u') out.pop_back(), i_ += 4, out += '?';  // not produced for our ASCII keys
    }
    ++i_;
    return out;
  }
  std::string scalar() {
    if (peek() == '"') return string();
    const size_t start = i_;
    while (i_ < s_.size() && std::string(",}] \t\r\n").find(s_[i_]) == std::string::npos) ++i_;
    return s_.substr(start, i_ - start);
  }
  void skip() {
    const char c = peek();
    if (c == '{' || c == '[') {
      const char close = c == '{' ? '}' : ']';
      ++i_;
      if (peek() == close) {
        ++i_;
        return;
      }
      while (true) {
        if (c == '{') {
          string();
          peek();
          ++i_;  // ':'
        }
        skip();
        if (peek() == ',') {
          ++i_;
          continue;
        }
        ++i_;  // close
        return;
      }
    }
    scalar();
  }
  std::optional<std::string> find(const std::vector<std::string>& path, size_t depth) {
    if (depth == path.size()) {
      const char c = peek();
      if (c == '{' || c == '[') return std::nullopt;
      return scalar();
    }
    if (peek() != '{') return std::nullopt;
    ++i_;
    if (peek() == '}') return std::nullopt;
    while (true) {
      if (peek() != '"') return std::nullopt;
      const std::string key = string();
      if (peek() != ':') return std::nullopt;
      ++i_;
      if (key == path[depth]) return find(path, depth + 1);
      skip();
      if (peek() != ',') return std::nullopt;
      ++i_;
    }
  }

  std::string s_;
  size_t i_ = 0;
};

// ------------------------------------------------------------------------------------------------ run data

/// One run's CSV log with its column names and units split, and the summary's scalars.
struct Run {
  std::string dir, csv;        ///< absolute paths
  std::string experiment, type, status;
  std::string var;             ///< gnuplot variable holding the CSV path
  CsvTable table;
  std::vector<std::string> names, units;
  std::function<std::optional<std::string>(const std::vector<std::string>&)> param;  ///< summary.json lookup

  /// Column index of the base name `name` (exact), -1 if absent.
  int col(const std::string& name) const {
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return static_cast<int>(i);
    return -1;
  }
  int time() const { return std::max(col("time"), 0); }
  /// Columns whose base name satisfies `pred`, in file order.
  std::vector<int> where(const std::function<bool(const std::string&)>& pred) const {
    std::vector<int> out;
    for (size_t i = 0; i < names.size(); ++i)
      if (static_cast<int>(i) != time() && pred(names[i])) out.push_back(static_cast<int>(i));
    return out;
  }
  double maxAbs(int c) const { return table.rows() ? table.data.col(c).cwiseAbs().maxCoeff() : 0.0; }
  double span(int c) const { return table.rows() ? table.data.col(c).maxCoeff() - table.data.col(c).minCoeff() : 0.0; }
  std::string unit(int c) const { return units[static_cast<size_t>(c)]; }
  std::string param1(const std::vector<std::string>& path) const {
    return param ? param(path).value_or("") : std::string();
  }
};

/// Reads RUN_DIR/summary.json and the CSV log it names.
Run loadRun(const std::string& run_dir) {
  Run run;
  run.dir = fs::absolute(run_dir).lexically_normal().string();
  const std::string summary_path = (fs::path(run.dir) / "summary.json").string();
  auto peek = std::make_shared<JsonPeek>(readTextFile(summary_path));
  run.param = [peek](const std::vector<std::string>& path) { return peek->get(path); };
  run.experiment = peek->get({"experiment"}).value_or("");
  run.type = peek->get({"type"}).value_or("");
  run.status = peek->get({"status"}).value_or("");
  // The log: DIR/<experiment>.csv; else the file named by "csv" (the folder may have been moved).
  std::vector<fs::path> candidates;
  if (!run.experiment.empty()) candidates.push_back(fs::path(run.dir) / (run.experiment + ".csv"));
  if (const auto csv = peek->get({"csv"})) {
    candidates.push_back(fs::path(run.dir) / fs::path(*csv).filename());
    candidates.push_back(fs::path(*csv));
  }
  for (const auto& c : candidates)
    if (fs::is_regular_file(c)) {
      run.csv = fs::absolute(c).lexically_normal().string();
      break;
    }
  if (run.csv.empty()) {
    std::string why = run.status == "failed" ? " (the run failed: " + run.param1({"reason"}) + ")" : "";
    throw InputError(summary_path + ": no CSV log to plot" + why + "; expected " +
                     (candidates.empty() ? std::string("<experiment>.csv") : candidates.front().string()));
  }
  if (run.experiment.empty()) run.experiment = fs::path(run.csv).stem().string();
  run.table = readCsv(run.csv, false);
  for (const auto& h : run.table.header) {
    auto [name, unit] = splitHeader(h);
    run.names.push_back(name);
    run.units.push_back(unit);
  }
  return run;
}

// ------------------------------------------------------------------------------------------------ figure model

struct Series {
  std::string data;       ///< gnuplot expression naming the data: a path variable or a datablock ($name)
  std::string using_;     ///< the `using` specification
  std::string title;      ///< legend entry (empty: none)
  std::string style = "lines";  ///< what follows `with`
  double magnitude = 0;   ///< max |y|, for the automatic right axis (0: stays on the left)
  bool header = true;     ///< the data start with a header line to skip
  bool y2 = false;        ///< on the right axis
};

enum class Key { automatic, top_left, top_right, bottom_right, outside, none };

struct Panel {
  std::string title, xlabel, ylabel, y2label;
  std::vector<Series> series;
  bool time_axis = true;  ///< x is time: no padding at the ends
  bool auto_y2 = false;   ///< series much smaller than the largest go to a right axis of the same unit
  Key key = Key::automatic;
  double y2_step = 0;     ///< right-axis tic step (0: about five tics over the left axis' span)
  std::string settings;   ///< extra gnuplot commands for this panel
};

struct Figure {
  std::string stem;   ///< file name without extension
  std::string title;  ///< figure title (starts with the experiment name)
  int rows = 1, cols = 1;
  std::vector<Panel> panels;
};

/// Multiplot grid of n panels: up to 3 columns.
void grid(Figure& f, size_t n, size_t max_cols = 3) {
  f.cols = static_cast<int>(std::min(std::max<size_t>(n, 1), max_cols));
  f.rows = static_cast<int>((std::max<size_t>(n, 1) + static_cast<size_t>(f.cols) - 1) / static_cast<size_t>(f.cols));
}

/// A signal scaled into a readable unit: m -> mm/µm, rad -> mrad/µrad when the values are small.
struct Scaled {
  double factor = 1;
  std::string unit;
};
Scaled readableUnit(const std::string& unit, double max_abs) {
  if ((unit == "m" || unit == "rad") && max_abs > 0) {
    if (max_abs < 5e-5) return {1e6, "µ" + unit};
    if (max_abs < 5e-2) return {1e3, "m" + unit};
  }
  return {1, unit};
}

/// y = column c (times `factor`) against time.
Series timeSeries(const Run& run, int c, const std::string& title, double factor = 1,
                  const std::string& style = "lines") {
  Series s;
  s.data = run.var;
  const std::string t = std::to_string(run.time() + 1), y = std::to_string(c + 1);
  s.using_ = factor == 1 ? t + ":" + y : t + ":($" + y + "*" + num(factor) + ")";
  s.title = title;
  s.style = style;
  s.magnitude = run.maxAbs(c) * std::abs(factor);
  return s;
}

/// y = column c against column x.
Series xySeries(const Run& run, int x, int c, const std::string& title, const std::string& style = "lines") {
  Series s;
  s.data = run.var;
  s.using_ = std::to_string(x + 1) + ":" + std::to_string(c + 1);
  s.title = title;
  s.style = style;
  s.magnitude = run.maxAbs(c);
  return s;
}

/// A time panel of the given columns (legend: the column names with `strip` removed); y label from `quantity`
/// and the first column's unit.
Panel timePanel(const Run& run, const std::vector<int>& cols, const std::string& title, const std::string& quantity,
                const std::function<std::string(const std::string&)>& legend = {}) {
  Panel p;
  p.title = title;
  p.xlabel = label("time", run.unit(run.time()));
  p.ylabel = cols.empty() ? quantity : label(quantity, run.unit(cols.front()));
  for (int c : cols) {
    const std::string& name = run.names[static_cast<size_t>(c)];
    p.series.push_back(timeSeries(run, c, legend ? legend(name) : name));
  }
  return p;
}

std::string stripPrefix(const std::string& s, const std::string& prefix) {
  return startsWith(s, prefix) ? s.substr(prefix.size()) : s;
}

// ------------------------------------------------------------------------------------------------ figures per type

/// Joint names of the columns `<prefix><joint>` (in file order).
std::vector<std::string> jointsWithPrefix(const Run& run, const std::string& prefix) {
  std::vector<std::string> joints;
  for (int c : run.where([&](const std::string& n) { return startsWith(n, prefix); }))
    joints.push_back(run.names[static_cast<size_t>(c)].substr(prefix.size()));
  return joints;
}

std::vector<Figure> passiveRobotFigures(const Run& run) {
  std::vector<Figure> figs;
  const auto joints = jointsWithPrefix(run, "q_");
  Figure f{run.experiment + "_joints", run.experiment + ": joint motion", 1, 1, {}};
  std::vector<int> q, qd, tip;
  for (const auto& j : joints) {
    if (run.col("q_" + j) >= 0) q.push_back(run.col("q_" + j));
    if (run.col("qd_" + j) >= 0) qd.push_back(run.col("qd_" + j));
  }
  for (const char* n : {"tip_x", "tip_y", "tip_z"})
    if (run.col(n) >= 0) tip.push_back(run.col(n));
  auto noPrefix = [](const std::string& p) { return [p](const std::string& n) { return stripPrefix(n, p); }; };
  if (!q.empty()) f.panels.push_back(timePanel(run, q, "joint angles", "joint angle", noPrefix("q_")));
  if (!qd.empty()) f.panels.push_back(timePanel(run, qd, "joint velocities", "joint velocity", noPrefix("qd_")));
  if (!tip.empty())
    f.panels.push_back(timePanel(run, tip, "tip position (world frame)", "tip position", noPrefix("tip_")));
  grid(f, f.panels.size(), 1);
  if (!f.panels.empty()) figs.push_back(f);

  const int ek = run.col("kinetic_energy"), ep = run.col("potential_energy"), et = run.col("total_energy");
  if (et >= 0 || ek >= 0 || ep >= 0) {
    Figure e{run.experiment + "_energy", run.experiment + ": energy", 1, 1, {}};
    std::vector<int> cols;
    for (int c : {ek, ep, et})
      if (c >= 0) cols.push_back(c);
    e.panels.push_back(timePanel(run, cols, "kinetic, potential and total energy", "energy"));
    if (et >= 0 && run.table.rows() > 0) {
      // Energy drift E(t) - E(0): zero for a conservative run, the integration error otherwise.
      const double e0 = run.table.data(0, et);
      Series s = timeSeries(run, et, "E(t) − E(0)");
      s.using_ = std::to_string(run.time() + 1) + ":($" + std::to_string(et + 1) + "-(" + num(e0) + "))";
      Panel drift;
      drift.title = "change of the total energy since t = 0";
      drift.xlabel = label("time", run.unit(run.time()));
      drift.ylabel = label("E(t) − E(0)", run.unit(et));
      drift.series.push_back(s);
      e.panels.push_back(drift);
    }
    grid(e, e.panels.size(), 1);
    figs.push_back(e);
  }
  return figs;
}

std::vector<Figure> trackingFigures(const Run& run) {
  std::vector<Figure> figs;
  const auto joints = jointsWithPrefix(run, "q_set_");
  if (joints.empty()) return figs;
  const std::string t = std::to_string(run.time() + 1);
  // Tracking error q_set - q, in mrad (or µrad) when small.
  double max_err = 0;
  for (const auto& j : joints) {
    const int cs = run.col("q_set_" + j), cq = run.col("q_" + j);
    if (cs >= 0 && cq >= 0 && run.table.rows())
      max_err = std::max(max_err, (run.table.data.col(cs) - run.table.data.col(cq)).cwiseAbs().maxCoeff());
  }
  const Scaled err = readableUnit("rad", max_err);
  Figure e{run.experiment + "_tracking_error", run.experiment + ": tracking error per joint", 1, 1, {}};
  Figure tq{run.experiment + "_torques", run.experiment + ": gear torque vs. inverse-dynamics reference", 1, 1, {}};
  Figure q{run.experiment + "_joint_angles", run.experiment + ": joint angles, set point and actual", 1, 1, {}};
  Figure cur{run.experiment + "_currents", run.experiment + ": motor currents", 1, 1, {}};
  for (const auto& j : joints) {
    const int cs = run.col("q_set_" + j), cq = run.col("q_" + j);
    if (cq >= 0) {
      Panel p;
      p.title = j;
      p.xlabel = label("time", run.unit(run.time()));
      p.ylabel = label("q_set − q", err.unit);
      Series s = timeSeries(run, cs, "q_set − q");
      s.using_ = t + ":(($" + std::to_string(cs + 1) + "-$" + std::to_string(cq + 1) + ")*" + num(err.factor) + ")";
      p.series.push_back(s);
      e.panels.push_back(p);
      Panel a;
      a.title = j;
      a.xlabel = p.xlabel;
      a.ylabel = label("joint angle", run.unit(cq));
      a.series.push_back(timeSeries(run, cs, "q_set", 1, "lines dt 2 lw 2"));
      a.series.push_back(timeSeries(run, cq, "q"));
      q.panels.push_back(a);
    }
    std::vector<Series> torques;
    const int cg = run.col("gear_torque_" + j), ci = run.col("id_torque_" + j), cf = run.col("friction_torque_" + j);
    if (cg >= 0) torques.push_back(timeSeries(run, cg, "gear torque"));
    if (ci >= 0) torques.push_back(timeSeries(run, ci, "inverse dynamics (reference)", 1, "lines dt 2 lw 2"));
    if (cf >= 0) torques.push_back(timeSeries(run, cf, "friction torque"));
    if (!torques.empty()) {
      Panel p;
      p.title = j;
      p.xlabel = label("time", run.unit(run.time()));
      p.ylabel = label("torque", run.unit(cg >= 0 ? cg : ci >= 0 ? ci : cf));
      p.series = torques;
      tq.panels.push_back(p);
    }
    const int cc = run.col("current_" + j), cr = run.col("current_ref_" + j);
    if (cc >= 0) {
      Panel p;
      p.title = j;
      p.xlabel = label("time", run.unit(run.time()));
      p.ylabel = label("motor current", run.unit(cc));
      if (cr >= 0) p.series.push_back(timeSeries(run, cr, "reference", 1, "lines dt 2 lw 2"));
      p.series.push_back(timeSeries(run, cc, "current"));
      cur.panels.push_back(p);
    }
  }
  for (Figure* f : {&e, &tq, &q, &cur})
    if (!f->panels.empty()) {
      grid(*f, f->panels.size());
      figs.push_back(*f);
    }
  return figs;
}

/// Mean friction torque and velocity over the settled end (last 30 %) of each constant, non-zero plateau of
/// the velocity reference: the steady-state points of the static friction map, as a datablock "v,tau".
std::string plateauMeans(const Run& run, int ref, int vel, int fric) {
  std::string block;
  const auto& d = run.table.data;
  Eigen::Index start = 0;
  for (Eigen::Index i = 1; i <= d.rows(); ++i) {
    if (i < d.rows() && d(i, ref) == d(start, ref)) continue;
    const Eigen::Index n = i - start;
    if (d(start, ref) != 0 && n >= 10) {
      const Eigen::Index from = start + (n * 7) / 10;
      const Eigen::Index m = i - from;
      const double v = d.col(vel).segment(from, m).mean(), tau = d.col(fric).segment(from, m).mean();
      block += num(v) + "," + num(tau) + "\n";
    }
    start = i;
  }
  return block;
}

std::vector<Figure> jointRigFigures(const Run& run, std::map<std::string, std::string>& blocks) {
  std::vector<Figure> figs;
  auto cols = [&](std::initializer_list<const char*> names) {
    std::vector<int> out;
    for (const char* n : names)
      if (run.col(n) >= 0) out.push_back(run.col(n));
    return out;
  };
  Figure f{run.experiment + "_signals", run.experiment + ": drive signals", 1, 1, {}};
  const auto angles = cols({"motor_angle", "output_angle"});
  const auto speeds = cols({"motor_velocity", "output_velocity", "reference_velocity"});
  const auto torques = cols({"motor_torque", "command_torque", "transmission_torque_in", "transmission_torque_out",
                             "friction_torque"});
  const auto electric = cols({"motor_current", "motor_voltage"});
  if (!angles.empty()) f.panels.push_back(timePanel(run, angles, "angles", "angle"));
  if (!speeds.empty()) f.panels.push_back(timePanel(run, speeds, "velocities", "velocity"));
  if (!torques.empty()) f.panels.push_back(timePanel(run, torques, "torques", "torque"));
  if (!electric.empty()) {
    Panel p = timePanel(run, electric, "motor electrics", "current");
    p.ylabel = label("motor current", run.unit(electric.front()));
    if (electric.size() == 2) {
      p.series[1].y2 = true;
      p.y2label = label("motor voltage", run.unit(electric[1]));
    }
    f.panels.push_back(p);
  }
  for (auto& p : f.panels) p.auto_y2 = true;
  grid(f, f.panels.size(), f.panels.size() == 4 ? 2 : 1);
  if (!f.panels.empty()) figs.push_back(f);

  const int ma = run.col("motor_angle"), mt = run.col("motor_torque"), oa = run.col("output_angle");
  const int ov = run.col("output_velocity"), mv = run.col("motor_velocity"), ft = run.col("friction_torque");
  const int rv = run.col("reference_velocity");
  // A clamped rig: the clamping curve (motor torque against motor angle).
  const std::string clamped = run.param1({"parameters", "load", "clamped"});
  const bool is_clamped = clamped == "true" || (clamped.empty() && (oa < 0 || run.maxAbs(oa) == 0));
  if (is_clamped && ma >= 0 && mt >= 0) {
    Figure c{run.experiment + "_clamping_curve", run.experiment + ": clamping curve", 1, 1, {}};
    Panel p;
    p.title = "motor torque against motor angle (output clamped)";
    p.xlabel = label("motor angle", run.unit(ma));
    p.ylabel = label("torque", run.unit(mt));
    p.time_axis = false;
    p.key = Key::top_left;
    p.series.push_back(xySeries(run, ma, mt, "motor torque"));
    const int ti = run.col("transmission_torque_in");
    if (ti >= 0) p.series.push_back(xySeries(run, ma, ti, "transmission torque (motor side)", "lines dt 2 lw 2"));
    c.panels.push_back(p);
    figs.push_back(c);
  }
  // A velocity-controlled rig with friction: the friction map (friction torque against velocity on the
  // friction side), every sample plus the steady state of each reference plateau.
  const std::string input = run.param1({"parameters", "input", "type"});
  const bool velocity_input = input == "velocity_pi" || (input.empty() && rv >= 0);
  if (velocity_input && ft >= 0 && !is_clamped) {
    const std::string side = run.param1({"parameters", "friction", "side"});
    const int v = (side == "motor" || ov < 0) ? mv : ov;
    if (v >= 0) {
      Figure m{run.experiment + "_friction_map", run.experiment + ": friction map", 1, 1, {}};
      Panel p;
      p.title = "friction torque against " + run.names[static_cast<size_t>(v)];
      p.xlabel = label(run.names[static_cast<size_t>(v)], run.unit(v));
      p.ylabel = label("friction torque", run.unit(ft));
      p.time_axis = false;
      p.key = Key::top_left;
      p.series.push_back(xySeries(run, v, ft, "all samples", "points pt 7 ps 0.3 lc rgb '#a0a0a0'"));
      if (rv >= 0) {
        const std::string block = plateauMeans(run, rv, v, ft);
        if (!block.empty()) {
          blocks["$plateaus"] = block;
          Series s;
          s.data = "$plateaus";
          s.header = false;
          s.using_ = "1:2";
          s.title = "steady state of each velocity plateau";
          s.style = "points pt 7 ps 1.6 lc rgb '#d62728'";
          p.series.push_back(s);
        }
      }
      m.panels.push_back(p);
      figs.push_back(m);
    }
  }
  return figs;
}

std::vector<Figure> clampingFigures(const Run& run) {
  std::vector<Figure> figs;
  std::vector<std::string> axes;
  for (int c : run.where([](const std::string& n) { return endsWith(n, ".motor_angle"); })) {
    const std::string a = run.names[static_cast<size_t>(c)].substr(0, run.names[static_cast<size_t>(c)].size() - 12);
    if (run.col(a + ".motor_torque") >= 0) axes.push_back(a);
  }
  Figure curves{run.experiment + "_clamping_curves",
                run.experiment + ": clamping curves (motor torque against motor angle)", 1, 1, {}};
  Figure torques{run.experiment + "_axis_torques", run.experiment + ": torques per axis", 1, 1, {}};
  for (const auto& a : axes) {
    const int ma = run.col(a + ".motor_angle"), mt = run.col(a + ".motor_torque");
    const int st = run.col(a + ".spring_torque"), ft = run.col(a + ".friction_torque");
    Panel p;
    p.title = a + (run.span(ma) == 0 ? " (not driven)" : "");
    p.xlabel = label("motor angle", run.unit(ma));
    p.ylabel = label("torque", run.unit(mt));
    p.time_axis = false;
    p.key = Key::top_left;
    p.series.push_back(xySeries(run, ma, mt, "motor torque"));
    if (st >= 0) p.series.push_back(xySeries(run, ma, st, "spring torque", "lines dt 2 lw 2"));
    curves.panels.push_back(p);
    std::vector<int> cols{mt};
    if (st >= 0) cols.push_back(st);
    if (ft >= 0) cols.push_back(ft);
    Panel t = timePanel(run, cols, a, "torque", [&](const std::string& n) { return stripPrefix(n, a + "."); });
    torques.panels.push_back(t);
  }
  for (Figure* f : {&curves, &torques})
    if (!f->panels.empty()) {
      grid(*f, f->panels.size());
      figs.push_back(*f);
    }
  // The clamp: displacement and rotation of the held frame, force and moment.
  Figure clamp{run.experiment + "_clamp", run.experiment + ": clamp displacement, rotation and load", 1, 1, {}};
  auto clampPanel = [&](std::initializer_list<const char*> names, const std::string& title, const std::string& q) {
    std::vector<int> cols;
    for (const char* n : names)
      if (run.col(n) >= 0) cols.push_back(run.col(n));
    if (cols.empty()) return;
    double m = 0;
    for (int c : cols) m = std::max(m, run.maxAbs(c));
    const Scaled s = readableUnit(run.unit(cols.front()), m);
    Panel p;
    p.title = title;
    p.xlabel = label("time", run.unit(run.time()));
    p.ylabel = label(q, s.unit);
    for (int c : cols)
      p.series.push_back(timeSeries(run, c, stripPrefix(run.names[static_cast<size_t>(c)], "clamp."), s.factor,
                                    endsWith(run.names[static_cast<size_t>(c)], "displacement") ||
                                            endsWith(run.names[static_cast<size_t>(c)], "rotation")
                                        ? "lines lw 2.5 lc rgb '#000000'"
                                        : "lines"));
    clamp.panels.push_back(p);
  };
  clampPanel({"clamp.dx", "clamp.dy", "clamp.dz", "clamp.displacement"}, "displacement (world frame)", "displacement");
  clampPanel({"clamp.rx", "clamp.ry", "clamp.rz", "clamp.rotation"}, "rotation vector (frame axes)", "rotation");
  clampPanel({"clamp.force"}, "force magnitude", "force");
  clampPanel({"clamp.moment"}, "moment magnitude", "moment");
  grid(clamp, clamp.panels.size(), 2);
  if (!clamp.panels.empty()) figs.push_back(clamp);
  return figs;
}

std::vector<Figure> driveChainFigures(const Run& run) {
  std::vector<Figure> figs;
  auto suffix = [&](const std::string& s) { return run.where([s](const std::string& n) { return endsWith(n, s); }); };
  auto owner = [](const std::string& n) { return n.substr(0, n.rfind('.')); };
  Figure in{run.experiment + "_inertias", run.experiment + ": inertias", 1, 1, {}};
  if (auto c = suffix(".phi"); !c.empty()) in.panels.push_back(timePanel(run, c, "angles", "angle", owner));
  if (auto c = suffix(".w"); !c.empty())
    in.panels.push_back(timePanel(run, c, "angular velocities", "angular velocity", owner));
  grid(in, in.panels.size(), 1);
  if (!in.panels.empty()) figs.push_back(in);
  Figure el{run.experiment + "_elements", run.experiment + ": elements", 1, 1, {}};
  if (auto c = suffix(".tau"); !c.empty()) el.panels.push_back(timePanel(run, c, "element torques", "torque", owner));
  if (auto c = suffix(".phi_rel"); !c.empty())
    el.panels.push_back(timePanel(run, c, "relative angles (to − from)", "relative angle", owner));
  if (auto c = suffix(".mode"); !c.empty()) {
    Panel p = timePanel(run, c, "friction modes (−1 backward, 0 stuck, +1 forward, 2 free)", "mode", owner);
    for (auto& s : p.series) s.style = "steps lw 2";
    p.settings = "set ytics 1\nset yrange [-1.5:2.5]\n";
    el.panels.push_back(p);
  }
  grid(el, el.panels.size(), 1);
  if (!el.panels.empty()) figs.push_back(el);
  return figs;
}

std::vector<Figure> robotR3AxisFigures(const Run& run) {
  std::vector<Figure> figs;
  auto find = [&](const std::string& suffix) {
    const auto c = run.where([&](const std::string& n) { return endsWith(n, suffix); });
    return c.empty() ? -1 : c.front();
  };
  Figure f{run.experiment + "_axis", run.experiment + ": axis signals", 1, 1, {}};
  const int phi = find("initializeFlange.phi_flange"), w = find("initializeFlange.w_flange");
  const int i = find("motor.La.i"), iref = find("motor.i_ref"), v = find("motor.C.v");
  const int defl = find("gear.spring.phi_rel"), tf = find("bearingFriction.tau"), mode = find("bearingFriction.mode");
  if (phi >= 0) {
    Panel p = timePanel(run, {phi}, "load", "load angle", [](const std::string&) { return "load angle"; });
    if (w >= 0) {
      p.series.push_back(timeSeries(run, w, "load speed (right axis)"));
      p.series.back().y2 = true;
      p.y2label = label("load speed", run.unit(w));
    }
    f.panels.push_back(p);
  }
  if (i >= 0) {
    Panel p = timePanel(run, {i}, "motor current", "motor current", [](const std::string&) { return "current La.i"; });
    if (iref >= 0) p.series.push_back(timeSeries(run, iref, "reference i_ref", 1, "lines dt 2 lw 2"));
    if (v >= 0) {
      p.series.push_back(timeSeries(run, v, "capacitor voltage C.v (right axis)"));
      p.series.back().y2 = true;
      p.y2label = label("voltage", run.unit(v));
    }
    f.panels.push_back(p);
  }
  if (defl >= 0) f.panels.push_back(timePanel(run, {defl}, "gear spring deflection", "deflection φ_rel",
                                              [](const std::string&) { return "gear.spring.phi_rel"; }));
  if (tf >= 0) {
    Panel p = timePanel(run, {tf}, "bearing friction", "friction torque",
                        [](const std::string&) { return "friction torque"; });
    if (mode >= 0) {
      p.series.push_back(timeSeries(run, mode, "mode (right axis)", 1, "steps"));
      p.series.back().y2 = true;
      p.y2label = "mode (−1, 0, +1)";
      p.y2_step = 1;
    }
    f.panels.push_back(p);
  }
  grid(f, f.panels.size(), 2);
  if (!f.panels.empty()) figs.push_back(f);
  if (auto e = run.where([](const std::string& n) { return startsWith(n, "energy."); }); !e.empty()) {
    Figure ef{run.experiment + "_energy", run.experiment + ": energy bookkeeping", 1, 1, {}};
    ef.panels.push_back(timePanel(run, e, "integrated energies", "energy",
                                  [](const std::string& n) { return stripPrefix(n, "energy."); }));
    figs.push_back(ef);
  }
  return figs;
}

std::vector<Figure> robotR3FullFigures(const Run& run) {
  std::vector<Figure> figs;
  auto matching = [&](const std::string& prefix, const std::string& suffix) {
    return run.where([&](const std::string& n) { return startsWith(n, prefix) && endsWith(n, suffix); });
  };
  auto axisName = [](const std::string& n) { return n.substr(0, n.find('.')); };
  auto jointName = [](const std::string& n) { return "joint " + n.substr(11, n.find('.', 11) - 11); };
  Figure j{run.experiment + "_joints", run.experiment + ": joint motion", 1, 1, {}};
  if (auto c = matching("mechanics.r", ".phi"); !c.empty())
    j.panels.push_back(timePanel(run, c, "joint angles", "joint angle", jointName));
  if (auto c = matching("mechanics.r", ".w"); !c.empty())
    j.panels.push_back(timePanel(run, c, "joint speeds", "joint speed", jointName));
  grid(j, j.panels.size(), 1);
  if (!j.panels.empty()) figs.push_back(j);
  Figure d{run.experiment + "_drives", run.experiment + ": drives", 1, 1, {}};
  if (auto c = matching("axis", ".motor.La.i"); !c.empty())
    d.panels.push_back(timePanel(run, c, "motor currents", "current", axisName));
  if (auto c = matching("axis", ".motor.C.v"); !c.empty())
    d.panels.push_back(timePanel(run, c, "motor voltages (C.v)", "voltage", axisName));
  if (auto c = matching("axis", ".gear.spring.phi_rel"); !c.empty())
    d.panels.push_back(timePanel(run, c, "gear spring deflections", "deflection", axisName));
  if (auto c = matching("axis", ".controller.PI.x"); !c.empty())
    d.panels.push_back(timePanel(run, c, "speed controller PI states", "PI.x", axisName));
  grid(d, d.panels.size(), 2);
  if (!d.panels.empty()) figs.push_back(d);
  return figs;
}

/// Every column against time, six panels per page: any experiment gets figures.
std::vector<Figure> genericFigures(const Run& run) {
  std::vector<Figure> figs;
  const auto cols = run.where([](const std::string&) { return true; });
  const size_t per_page = 6, pages = (cols.size() + per_page - 1) / per_page;
  for (size_t page = 0; page < pages; ++page) {
    Figure f{run.experiment + "_columns_" + std::to_string(page + 1),
             run.experiment + ": all columns (" + std::to_string(page + 1) + "/" + std::to_string(pages) + ")", 1, 1,
             {}};
    for (size_t k = page * per_page; k < std::min(cols.size(), (page + 1) * per_page); ++k) {
      const int c = cols[k];
      const std::string& n = run.names[static_cast<size_t>(c)];
      f.panels.push_back(timePanel(run, {c}, n, n));
      f.panels.back().key = Key::none;
    }
    grid(f, f.panels.size());
    figs.push_back(f);
  }
  return figs;
}

std::vector<Figure> runFigures(const Run& run, std::map<std::string, std::string>& blocks) {
  std::vector<Figure> figs;
  if (run.type == "passive_robot") figs = passiveRobotFigures(run);
  else if (run.type == "tracking") figs = trackingFigures(run);
  else if (run.type == "joint_rig") figs = jointRigFigures(run, blocks);
  else if (run.type == "clamping") figs = clampingFigures(run);
  else if (run.type == "drive_chain") figs = driveChainFigures(run);
  else if (run.type == "robotr3_axis") figs = robotR3AxisFigures(run);
  else if (run.type == "robotr3_full") figs = robotR3FullFigures(run);
  if (figs.empty()) figs = genericFigures(run);  // unknown type, or none of the expected columns
  return figs;
}

// ------------------------------------------------------------------------------------------------ sweeps

struct ManifestRow {
  std::string run, status, output_dir, overrides;
  double wall_time_s = NAN, sim_time_s = NAN, real_time_factor = NAN;
};

/// One CSV record with RFC 4180 quoting ("a ""b""" -> a "b").
std::vector<std::string> splitCsvRecord(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') cells.back() += '"', ++i;
      else if (c == '"') quoted = false;
      else cells.back() += c;
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cells.emplace_back();
    } else if (c != '\r') {
      cells.back() += c;
    }
  }
  return cells;
}

std::vector<ManifestRow> readManifest(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open for reading");
  const std::vector<std::string> expected{"run", "status", "wall_time_s", "sim_time_s", "real_time_factor",
                                          "output_dir", "overrides"};
  std::string line;
  int line_no = 0;
  std::vector<ManifestRow> rows;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const auto cells = splitCsvRecord(line);
    if (line_no == 1) {
      if (cells != expected)
        throw InputError(path + ":1: expected the header run,status,wall_time_s,sim_time_s,real_time_factor,"
                         "output_dir,overrides");
      continue;
    }
    if (cells.size() != expected.size())
      throw InputError(path + ":" + std::to_string(line_no) + ": expected 7 cells, got " +
                       std::to_string(cells.size()));
    auto number = [](const std::string& s) {
      char* end = nullptr;
      const double x = std::strtod(s.c_str(), &end);
      return (s.empty() || *end != '\0') ? NAN : x;
    };
    ManifestRow r;
    r.run = cells[0];
    r.status = cells[1];
    r.wall_time_s = number(cells[2]);
    r.sim_time_s = number(cells[3]);
    r.real_time_factor = number(cells[4]);
    r.output_dir = cells[5];
    r.overrides = cells[6];
    rows.push_back(r);
  }
  if (rows.empty()) throw InputError(path + ": no runs listed");
  return rows;
}

/// The run folder of a manifest row: output_dir as written (absolute, or relative to the working directory),
/// else relative to the sweep folder, else SWEEP_DIR/<its last component> or SWEEP_DIR/<run>.
std::optional<std::string> runFolder(const std::string& sweep_dir, const ManifestRow& row) {
  std::vector<fs::path> candidates;
  if (!row.output_dir.empty()) {
    const fs::path p(row.output_dir);
    candidates.push_back(p);
    if (p.is_relative()) candidates.push_back(fs::path(sweep_dir) / p);
    candidates.push_back(fs::path(sweep_dir) / p.filename());
  }
  candidates.push_back(fs::path(sweep_dir) / row.run);
  for (const auto& c : candidates)
    if (fs::is_regular_file(c / "summary.json")) return c.string();
  return std::nullopt;
}

/// The signal that sums up one run of an experiment type, for the overlay across a sweep's runs.
struct KeySignal {
  std::string x, y, y_minus;  ///< base column names; y_minus is subtracted from y when set
  double factor = 1;
  std::string xlabel, ylabel, what;
};

std::optional<KeySignal> keySignal(const Run& run) {
  const std::string time_label = label("time", run.unit(run.time()));
  const std::string time_name = run.names[static_cast<size_t>(run.time())];
  auto timeKey = [&](int c, const std::string& what) {
    KeySignal k;
    k.x = time_name;
    k.y = run.names[static_cast<size_t>(c)];
    k.xlabel = time_label;
    k.ylabel = label(k.y, run.unit(c));
    k.what = what;
    return k;
  };
  if (run.type == "tracking") {
    const auto joints = jointsWithPrefix(run, "q_set_");
    if (!joints.empty() && run.col("q_" + joints[0]) >= 0 && run.table.rows() > 0) {
      const int cs = run.col("q_set_" + joints[0]), cq = run.col("q_" + joints[0]);
      KeySignal k;
      k.x = time_name;
      k.y = "q_set_" + joints[0];
      k.y_minus = "q_" + joints[0];
      const Scaled s = readableUnit("rad", (run.table.data.col(cs) - run.table.data.col(cq)).cwiseAbs().maxCoeff());
      k.factor = s.factor;
      k.xlabel = time_label;
      k.ylabel = label("q_set − q", s.unit);
      k.what = "tracking error of " + joints[0];
      return k;
    }
  }
  auto curve = [&](const std::string& prefix, const std::string& what) -> std::optional<KeySignal> {
    const int ma = run.col(prefix + "motor_angle"), mt = run.col(prefix + "motor_torque");
    if (ma < 0 || mt < 0) return std::nullopt;
    KeySignal k;
    k.x = prefix + "motor_angle";
    k.y = prefix + "motor_torque";
    k.xlabel = label("motor angle", run.unit(ma));
    k.ylabel = label("motor torque", run.unit(mt));
    k.what = what;
    return k;
  };
  if (run.type == "clamping") {
    std::string first;
    for (int c : run.where([](const std::string& n) { return endsWith(n, ".motor_angle"); })) {
      const std::string a = run.names[static_cast<size_t>(c)].substr(0, run.names[static_cast<size_t>(c)].size() - 12);
      if (first.empty()) first = a;
      if (run.span(c) > 0) {
        first = a;
        break;
      }
    }
    if (!first.empty())
      if (auto k = curve(first + ".", "clamping curve of " + first)) return k;
  }
  if (run.type == "joint_rig") {
    const int oa = run.col("output_angle");
    if (run.param1({"parameters", "load", "clamped"}) == "true" || (oa >= 0 && run.maxAbs(oa) == 0))
      if (auto k = curve("", "clamping curve")) return k;
    for (const char* n : {"output_velocity", "motor_velocity"})
      if (run.col(n) >= 0) return timeKey(run.col(n), n);
  }
  if (run.type == "passive_robot")
    if (auto q = jointsWithPrefix(run, "q_"); !q.empty()) return timeKey(run.col("q_" + q[0]), "angle of " + q[0]);
  if (run.type == "drive_chain")
    if (auto w = run.where([](const std::string& n) { return endsWith(n, ".w"); }); !w.empty())
      return timeKey(w[0], run.names[static_cast<size_t>(w[0])]);
  if (run.type == "robotr3_axis")
    if (auto c = run.where([](const std::string& n) { return endsWith(n, "phi_flange"); }); !c.empty())
      return timeKey(c[0], "load angle");
  if (run.type == "robotr3_full" && run.col("mechanics.r1.phi") >= 0)
    return timeKey(run.col("mechanics.r1.phi"), "angle of joint 1");
  if (auto c = run.where([](const std::string&) { return true; }); !c.empty())
    return timeKey(c[0], run.names[static_cast<size_t>(c[0])]);
  return std::nullopt;
}

/// Datablock-safe run name (the datablock is comma-separated).
std::string cellText(std::string s) {
  for (char& c : s)
    if (c == ',' || c == '"' || c == '\n') c = ' ';
  return "\"" + s + "\"";
}

struct SweepPlan {
  std::vector<Figure> figures;
  std::vector<Run> runs;  ///< the runs of the overlay (their `var` set)
  std::map<std::string, std::string> blocks;
};

double niceCeil(double x);  // below

SweepPlan sweepFigures(const std::string& sweep_dir) {
  SweepPlan plan;
  const std::string name = fs::path(sweep_dir).filename().string();
  const auto rows = readManifest((fs::path(sweep_dir) / "manifest.csv").string());
  // Per-run bars of wall time and real-time factor, coloured by status.
  const std::map<std::string, std::string> colours{{"ok", "0x2ca02c"}, {"failed", "0xd62728"}};
  std::string block;
  std::vector<std::string> statuses;
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto it = colours.find(rows[i].status);
    block += std::to_string(i) + "," + cellText(rows[i].run) + "," + num(rows[i].wall_time_s) + "," +
             num(rows[i].real_time_factor) + "," + (it == colours.end() ? "0x7f7f7f" : it->second) + "\n";
    if (std::find(statuses.begin(), statuses.end(), rows[i].status) == statuses.end())
      statuses.push_back(rows[i].status);
  }
  plan.blocks["$runs"] = block;
  // Horizontal bars (run names on the y axis, first run on top): long fault-run names stay readable.
  Figure bars{"sweep_runs", name + ": runs of the sweep (" + std::to_string(rows.size()) + ")", 1, 2, {}};
  const bool labels = rows.size() <= 60;
  const std::string yrange = "set yrange [" + num(static_cast<double>(rows.size()) - 0.4) + ":-0.6]\n";
  bool first = true;
  for (const auto& [col, quantity, title] :
       std::vector<std::tuple<int, std::string, std::string>>{{3, "wall time [s]", "wall-clock time per run"},
                                                              {4, "real-time factor (sim time / wall time)",
                                                               "real-time factor per run"}}) {
    double vmax = 0.0;  // at most about four labelled x tics: the first panel is narrow
    for (const auto& r : rows) vmax = std::max(vmax, col == 3 ? r.wall_time_s : r.real_time_factor);
    const std::string xtics = vmax > 0 ? "set xtics " + num(niceCeil(vmax / 4)) + "\n" : std::string();
    Panel p;
    p.title = title;
    p.xlabel = quantity;
    p.ylabel = "";
    p.time_axis = false;
    p.key = Key::bottom_right;
    p.settings = "set style fill solid 0.85 border lc rgb '#404040'\nset xrange [0:*]\nset grid xtics noytics\n" +
                 yrange + xtics + (first && labels ? std::string("set ytics scale 0 font ',9'\n")
                                           : std::string("set ytics scale 0 format ''\n"));
    Series s;
    s.data = "$runs";
    s.header = false;
    const std::string c = std::to_string(col);
    s.using_ = "(0.5*$" + c + "):1:(0):" + c + ":($1-0.35):($1+0.35):5" +
               (first && labels ? std::string(":ytic(2)") : std::string());
    s.style = "boxxyerror lc rgb variable";
    p.series.push_back(s);
    for (const auto& st : statuses) {  // legend entries: one per status
      const auto it = colours.find(st);
      Series l;
      l.data = "NaN";
      l.header = false;
      l.using_.clear();
      l.title = "status " + st;
      l.style = "boxes lc rgb '" + std::string("#") + (it == colours.end() ? "7f7f7f" : it->second.substr(2)) + "'";
      p.series.push_back(l);
    }
    bars.panels.push_back(p);
    first = false;
  }
  plan.figures.push_back(bars);

  // Overlay of the key signal across the runs that have a log of the same experiment.
  std::vector<std::pair<std::string, Run>> runs;
  for (const auto& row : rows) {
    const auto dir = runFolder(sweep_dir, row);
    if (!dir) continue;
    try {
      runs.emplace_back(row.run, loadRun(*dir));
    } catch (const InputError&) {
      // a failed run has no log: it only appears in the bars
    }
  }
  if (runs.empty()) return plan;
  for (const auto& [run_name, r] : runs)
    if (r.type != runs.front().second.type || r.experiment != runs.front().second.experiment) return plan;
  const auto key = keySignal(runs.front().second);
  if (!key) return plan;
  Figure overlay{"sweep_overlay", name + ": " + key->what + " across runs (" + runs.front().second.experiment + ")",
                 1, 1, {}};
  Panel p;
  p.title = key->what;
  p.xlabel = key->xlabel;
  p.ylabel = key->ylabel;
  p.time_axis = key->x == runs.front().second.names[static_cast<size_t>(runs.front().second.time())];
  p.key = Key::outside;
  if (runs.size() > 30) p.key = Key::none;
  for (size_t i = 0; i < runs.size(); ++i) {
    Run& r = runs[i].second;
    const int x = r.col(key->x), y = r.col(key->y), ym = key->y_minus.empty() ? -2 : r.col(key->y_minus);
    if (x < 0 || y < 0 || ym == -1) continue;
    r.var = "run" + std::to_string(plan.runs.size());
    Series s;
    s.data = r.var;
    s.title = runs[i].first;
    const std::string yexpr =
        "$" + std::to_string(y + 1) + (ym >= 0 ? "-$" + std::to_string(ym + 1) : std::string());
    s.using_ = std::to_string(x + 1) + ":((" + yexpr + ")*" + num(key->factor) + ")";
    p.series.push_back(s);
    plan.runs.push_back(r);
  }
  if (p.series.empty()) return plan;
  overlay.panels.push_back(p);
  plan.figures.push_back(overlay);
  return plan;
}

// ------------------------------------------------------------------------------------------------ gnuplot script

/// Standard look: white background, light grid, colour-blind-friendly line colours (matplotlib's tab10).
const char* kStyle =
    "set encoding utf8\n"
    "set datafile separator comma\n"
    "set grid lc rgb '#d8d8d8' lw 1 dt 1\n"
    "set border lw 1.2\n"
    "set tics out nomirror\n"
    "set mxtics\n"
    "set mytics\n"
    "set format y '%g'\n"
    "set format x '%g'\n";

const char* kLineTypes =
    "set linetype 1 lc rgb '#1f77b4' lw 1.6 pt 7\n"
    "set linetype 2 lc rgb '#d62728' lw 1.6 pt 7\n"
    "set linetype 3 lc rgb '#2ca02c' lw 1.6 pt 7\n"
    "set linetype 4 lc rgb '#ff7f0e' lw 1.6 pt 7\n"
    "set linetype 5 lc rgb '#9467bd' lw 1.6 pt 7\n"
    "set linetype 6 lc rgb '#8c564b' lw 1.6 pt 7\n"
    "set linetype 7 lc rgb '#e377c2' lw 1.6 pt 7\n"
    "set linetype 8 lc rgb '#7f7f7f' lw 1.6 pt 7\n"
    "set linetype 9 lc rgb '#bcbd22' lw 1.6 pt 7\n"
    "set linetype 10 lc rgb '#17becf' lw 1.6 pt 7\n"
    "set linetype cycle 10\n";

/// The smallest of 1, 2, 5 × 10^n that is at least x > 0.
double niceCeil(double x) {
  const double e = std::pow(10.0, std::floor(std::log10(x)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * e >= x * (1 - 1e-12)) return m * e;
  return 10 * e;
}

/// The `using` specification `x:y` with y divided by k.
std::string scaleY(const std::string& using_, double k) {
  const size_t colon = using_.find(':');
  const std::string x = using_.substr(0, colon), y = using_.substr(colon + 1);
  const bool plain =
      !y.empty() && std::all_of(y.begin(), y.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
  return x + ":((" + (plain ? "$" + y : y) + ")/" + num(k) + ")";
}

/// Moves series an order of magnitude smaller than the largest to a right axis of the same unit (auto_y2).
void resolveAxes(Panel& p) {
  if (p.auto_y2 && p.y2label.empty() && p.series.size() >= 2) {
    double largest = 0;
    for (const auto& s : p.series) largest = std::max(largest, s.magnitude);
    bool moved = false;
    for (auto& s : p.series)
      if (s.magnitude > 0 && s.magnitude < largest / 20) {
        s.y2 = true;
        s.title += " (right axis)";
        moved = true;
      }
    if (moved) p.y2label = p.ylabel + " (right axis)";
  }
  p.auto_y2 = false;
}

bool hasY2(const Panel& p) {
  return std::any_of(p.series.begin(), p.series.end(), [](const Series& s) { return s.y2; });
}

size_t titledSeries(const Panel& p) {
  return static_cast<size_t>(
      std::count_if(p.series.begin(), p.series.end(), [](const Series& s) { return !s.title.empty(); }));
}

Key effectiveKey(const Panel& p) {
  if (p.key != Key::automatic) return p.key;
  return titledSeries(p) > 4 ? Key::outside : Key::top_right;
}

/// Explicit right-axis tics i·step over ±span, labelled with %g of the rounded value (gnuplot's own
/// `start, step` tics accumulate rounding errors: a "0" tic would read -1.38778e-17).
std::string y2Tics(double step, double span) {
  const int n = static_cast<int>(std::min(200.0, std::ceil(span / step)));
  std::string out = "(";
  for (int i = -n; i <= n; ++i) {
    char text[40];
    std::snprintf(text, sizeof text, "%.6g", i * step);
    out += (i > -n ? ", " : "") + quote(text) + " " + num(i * step);
  }
  return out + ")";
}

/// gnuplot commands drawing one panel (its axes already resolved).
/// `key_at`: screen x of the legend of a stacked panel with an outside legend (left of the reserved column).
std::string renderPanel(const Panel& p, double key_at = 0) {
  // The right axis is linked to the left one, y2 = k·y with k a round number, so that both share zero and
  // the grid; right-axis series are drawn on the left axis divided by k (so autoscaling sees every series).
  double mag1 = 0, mag2 = 0;
  for (const auto& s : p.series) (s.y2 ? mag2 : mag1) = std::max(s.y2 ? mag2 : mag1, s.magnitude);
  const bool y2 = hasY2(p);
  const double k = (mag1 > 0 && mag2 > 0) ? niceCeil(mag2 / mag1) : 1.0;
  std::ostringstream o;
  o << "set title " << quote(p.title) << "\n";
  o << "set xlabel " << quote(p.xlabel) << "\n";
  o << "set ylabel " << quote(p.ylabel) << "\n";
  if (y2)
    o << "set y2label " << quote(p.y2label) << "\nset link y2 via y*" << num(k) << " inverse y/" << num(k)
      << "\nset y2tics " << y2Tics(p.y2_step > 0 ? p.y2_step : niceCeil(k * (mag1 > 0 ? mag1 : 1) / 5),
                                   1.6 * std::max(k * mag1, mag2)) << "\nunset my2tics\n";
  else
    o << "unset y2label\nunset link y2\nunset y2tics\nunset my2tics\n";
  o << (p.time_axis ? "set autoscale xfix\n" : "set autoscale x\n");
  const size_t titled = titledSeries(p);
  const Key key = effectiveKey(p);
  switch (key) {
    case Key::none: o << "unset key\n"; break;
    case Key::outside:
      if (key_at > 0)
        o << "set key at screen " << num(key_at) << ", graph 1 left top";
      else
        o << "set key outside right top";
      o << " vertical Left reverse noopaque nobox samplen 2\n";
      break;
    case Key::top_left: o << "set key inside top left Left reverse opaque box lc rgb '#b0b0b0' samplen 2\n"; break;
    case Key::bottom_right:
      o << "set key inside bottom right Left reverse opaque box lc rgb '#b0b0b0' samplen 2\n";
      break;
    default: o << "set key inside top right Left reverse opaque box lc rgb '#b0b0b0' samplen 2\n"; break;
  }
  // Headroom for a legend inside the plot, so it does not hide the curves' peaks.
  if (key == Key::top_left || key == Key::top_right)
    o << "set offsets 0, 0, graph " << num(0.1 * static_cast<double>(titled) + 0.04) << ", graph 0.03\n";
  else
    o << "set offsets 0, 0, graph 0.03, graph 0.03\n";
  o << p.settings;
  o << "plot ";
  for (size_t i = 0; i < p.series.size(); ++i) {
    const Series& s = p.series[i];
    o << (i ? ", \\\n     " : "") << s.data;
    if (s.header) o << " skip 1";
    if (!s.using_.empty()) o << " using " << (s.y2 ? scaleY(s.using_, k) : s.using_);
    o << " with " << s.style << (s.title.empty() ? std::string(" notitle") : " title " + quote(s.title));
  }
  o << "\n";
  // Reset what a panel may have changed for the next one.
  o << "set xtics norotate\nset autoscale y\nset autoscale y2\nset ytics autofreq\nset grid xtics ytics\n"
       "set style fill empty\n";
  return o.str();
}

std::string renderFigure(const Figure& f, const std::string& terminal, const std::string& output, double font_scale) {
  std::ostringstream o;
  o << "\n# ---- " << f.stem << "\n" << terminal << "\n";
  o << "set output " << quote(output) << ".outsuffix\n";
  o << "reset\n" << kStyle;
  std::vector<Panel> panels = f.panels;
  for (auto& p : panels) resolveAxes(p);
  o << "set multiplot layout " << f.rows << "," << f.cols << " title " << quote(f.title) << " font ',"
    << num(std::round(14 * font_scale)) << "'";
  double key_at = 0;
  if (f.cols == 1) {
    // Stacked time panels: equal margins so that their time axes line up; room on the right for legends
    // outside the plot and for a right axis.
    const bool outside =
        std::any_of(panels.begin(), panels.end(), [](const Panel& p) { return effectiveKey(p) == Key::outside; });
    const bool y2 = std::any_of(panels.begin(), panels.end(), hasY2);
    // Width of an outside legend: the longest entry (≈ 8 px per character at the 1400 px reference size,
    // plus the sample line), at least 16 % of the figure, at most 40 %.
    size_t longest = 0;
    for (const auto& p : panels)
      if (effectiveKey(p) == Key::outside)
        for (const auto& sr : p.series) longest = std::max(longest, sr.title.size());
    const double key_width = std::clamp((8.0 * static_cast<double>(longest) + 60.0) / 1400.0, 0.16, 0.40);
    const double right = 1 - (outside ? key_width : 0.02) - (y2 ? 0.06 : 0.0);
    if (outside) key_at = right + (y2 ? 0.07 : 0.01);
    o << " margins 0.08, " << num(right) << ", " << num(f.rows > 1 ? 0.07 : 0.09) << ", 0.91 spacing 0.1, 0.13";
  }
  o << "\n";
  for (const auto& p : panels) o << renderPanel(p, key_at);
  o << "unset multiplot\nset output\n";
  return o.str();
}

/// Runs `exe args...` with stdin and stdout on /dev/null and stderr into `stderr_path`; returns the exit status
/// (or -1 if it could not start, 128 + signal if killed).
int runProcess(const std::string& exe, const std::vector<std::string>& args, const std::string& stderr_path) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> argv_s{exe};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

/// Removes the listed files when it goes out of scope (temporary script, stderr capture, unrenamed figures).
struct Cleanup {
  std::vector<std::string> paths;
  ~Cleanup() {
    for (const auto& p : paths) std::remove(p.c_str());
  }
};

}  // namespace

std::string findGnuplot(const std::string& requested) {
  const std::string name = requested.empty() ? "gnuplot" : requested;
  auto executable = [](const fs::path& p) { return fs::is_regular_file(p) && ::access(p.c_str(), X_OK) == 0; };
  if (name.find('/') != std::string::npos) {
    if (executable(name)) return name;
  } else if (const char* path = std::getenv("PATH")) {
    std::stringstream ss(path);
    for (std::string dir; std::getline(ss, dir, ':');) {
      const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
      if (executable(candidate)) return candidate.string();
    }
  }
  throw InputError("gnuplot not found; install gnuplot-nox (scripts/install-deps.sh)" +
                   (requested.empty() ? std::string() : " (looked for '" + requested + "')"));
}

std::vector<std::string> plotRun(const std::string& run_dir, const std::string& fig_dir, const PlotOptions& options) {
  if (options.width < 200 || options.height < 150 || options.width > 10000 || options.height > 10000)
    throw InputError("plot size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                     " pixels: expected a width of 200 to 10000 and a height of 150 to 10000");
  if (!fs::is_directory(run_dir)) throw InputError(run_dir + ": no such run folder");
  const fs::path dir = fs::absolute(run_dir).lexically_normal();
  const bool is_run = fs::is_regular_file(dir / "summary.json");
  const bool is_sweep = !is_run && fs::is_regular_file(dir / "manifest.csv");
  if (!is_run && !is_sweep)
    throw InputError(run_dir + ": neither a run folder (summary.json and the CSV log of `jointsim run`) nor a sweep "
                     "folder (manifest.csv of `jointsim batch`)");
  const std::string gnuplot = findGnuplot(options.gnuplot);

  // What to draw.
  std::vector<Figure> figures;
  std::vector<Run> sources;
  std::map<std::string, std::string> blocks;
  std::string name;
  if (is_run) {
    Run run = loadRun(dir.string());
    run.var = "csv";
    figures = runFigures(run, blocks);
    name = run.experiment;
    sources.push_back(std::move(run));
  } else {
    SweepPlan plan = sweepFigures(dir.string());
    figures = std::move(plan.figures);
    sources = std::move(plan.runs);
    blocks = std::move(plan.blocks);
    name = "sweep";
  }

  const fs::path out_dir = fig_dir.empty() ? dir / "figures" : fs::absolute(fig_dir).lexically_normal();
  createDirectories(out_dir.string());

  // The script: data paths and blocks, then every figure as PNG (and SVG).
  const double font_scale = std::max(0.7, std::min(options.width / 1400.0, options.height / 900.0));
  const std::string font = "font 'DejaVu Sans," + num(std::round(11 * font_scale)) + "'";
  const std::string size = "size " + std::to_string(options.width) + "," + std::to_string(options.height);
  const std::string png =
      "set terminal pngcairo " + size + " noenhanced " + font + " linewidth 1 background rgb 'white'";
  const std::string svg = "set terminal svg " + size + " noenhanced " + font + " linewidth 1 background rgb 'white'";
  std::ostringstream body;
  body << "# Figures of " << dir.string() << ", written by `jointsim plot` (docs/plots.md).\n"
       << "# Rerun with: gnuplot THIS_FILE (figures are written to their final names)\n";
  for (const auto& r : sources) body << r.var << " = " << quote(r.csv) << "\n";
  for (const auto& [block_name, text] : blocks) body << block_name << " << EOD\n" << text << "EOD\n";
  body << kLineTypes;
  std::vector<std::string> finals;
  for (const auto& f : figures) {
    const std::string path = (out_dir / (f.stem + ".png")).string();
    body << renderFigure(f, png, path, font_scale);
    finals.push_back(path);
  }
  if (options.svg)
    for (const auto& f : figures) {
      const std::string path = (out_dir / (f.stem + ".svg")).string();
      body << renderFigure(f, svg, path, font_scale);
      finals.push_back(path);
    }

  // Run gnuplot on a temporary copy whose outputs carry a temporary suffix; rename them when it succeeded.
  const std::string suffix = ".tmp." + std::to_string(static_cast<long>(::getpid()));
  const std::string script = (out_dir / (".jointsim_plot" + suffix + ".gp")).string();
  const std::string errors = (out_dir / (".jointsim_plot" + suffix + ".err")).string();
  Cleanup cleanup;
  cleanup.paths = {script, errors};
  for (const auto& f : finals) cleanup.paths.push_back(f + suffix);
  writeFileAtomically(script, "outsuffix = " + quote(suffix) + "\n" + body.str());
  const int status = runProcess(gnuplot, {script}, errors);
  if (status != 0) {
    std::string err = readTextFile(errors);
    while (!err.empty() && std::isspace(static_cast<unsigned char>(err.back()))) err.pop_back();
    if (err.size() > 4000) err = "..." + err.substr(err.size() - 4000);
    throw Error("gnuplot (" + gnuplot + ") failed with exit status " + std::to_string(status) +
                " drawing the figures of " + dir.string() + (err.empty() ? std::string() : ":\n" + err));
  }
  for (const auto& f : finals) {
    if (!fs::is_regular_file(f + suffix)) throw Error(f + ": gnuplot did not write this figure");
    if (std::rename((f + suffix).c_str(), f.c_str()) != 0)
      throw Error(f + ": cannot move the figure into place: " + std::strerror(errno));
  }
  std::vector<std::string> written = finals;
  if (options.keep_script) {
    const std::string path = (out_dir / (name + "_plots.gp")).string();
    writeFileAtomically(path, "outsuffix = ''\n" + body.str());
    written.push_back(path);
  }
  return written;
}

}  // namespace jointsim::io
