#pragma once
/// \file
/// Figures of a run, described as data: each experiment type registers a function RunData → figures
/// (experiments/registry.hpp), and `jointsim plot` (report/plot.hpp) renders them (with gnuplot). The
/// description knows nothing of the renderer: a series names columns of the run's log (or carries its own
/// points), a style from a small set, a title; the renderer does all quoting.

#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

namespace jointsim::experiments {

/// A finished run as the figure builders see it: the log with column names and units split, and the
/// summary (summary.json) for parameters.
struct RunData {
  std::string experiment, type, status;
  std::vector<std::string> names, units;                  ///< per log column: base name and unit ("time", "s")
  Eigen::MatrixXd data;                                   ///< rows × columns of the log
  std::shared_ptr<const nlohmann::ordered_json> summary;  ///< may be null

  /// Column index of the base name `name` (exact), -1 if absent.
  int col(const std::string& name) const;
  /// The time column (0 if none is called "time").
  int time() const;
  /// Columns (other than time) whose base name satisfies `pred`, in file order.
  std::vector<int> where(const std::function<bool(const std::string&)>& pred) const;
  double maxAbs(int c) const;
  double span(int c) const;
  const std::string& unit(int c) const { return units[static_cast<size_t>(c)]; }
  const std::string& name(int c) const { return names[static_cast<size_t>(c)]; }
  /// A summary value at a key path (e.g. {"parameters", "load", "clamped"}) as text ("true", "0.5", a string);
  /// "" when absent or not a scalar.
  std::string param(const std::vector<std::string>& path) const;
};

/// How a series is drawn.
enum class LineStyle {
  Line,      ///< solid line in the next colour
  Dashed,    ///< thicker dashed line (references, set-points)
  Emphasis,  ///< thick black line (a norm drawn over its components)
  Steps,     ///< staircase (discrete values)
  ThickSteps,
  Samples,  ///< small grey dots (every sample of a scatter)
  Markers,  ///< large red dots (a few computed points)
};

/// One curve: y = ((log[y] − log[y_minus]) − offset) · factor against log[x] (x = −1: the time column), or the
/// given `points` when not empty.
struct Series {
  int x = -1, y = -1, y_minus = -1;
  double factor = 1.0, offset = 0.0;
  std::vector<std::array<double, 2>> points;
  std::string title;  ///< legend entry (empty: none)
  LineStyle style = LineStyle::Line;
  bool y2 = false;         ///< on the right axis
  double magnitude = 0.0;  ///< max |y|, for the automatic right axis
};

enum class Key { automatic, top_left, top_right, bottom_right, outside, none };

/// Titles, axes and legend of a panel (shared with the renderer's own panel type).
struct PanelLayout {
  std::string title, xlabel, ylabel, y2label;
  bool time_axis = true;  ///< x is time: no padding at the ends
  bool auto_y2 = false;   ///< series much smaller than the largest go to a right axis of the same unit
  Key key = Key::automatic;
  double y2_step = 0;  ///< right-axis tic step (0: about five tics over the left axis' span)
};

struct Panel : PanelLayout {
  std::vector<Series> series;
  double y_step = 0;                                        ///< left-axis tic step (0: automatic)
  double y_min = std::numeric_limits<double>::quiet_NaN();  ///< fixed left-axis range when both are set
  double y_max = std::numeric_limits<double>::quiet_NaN();
};

struct Figure {
  std::string stem;   ///< file name without extension
  std::string title;  ///< figure title (starts with the experiment name)
  int rows = 1, cols = 1;
  std::vector<Panel> panels;
};

/// The signal that sums up one run, overlaid across the runs of a sweep.
struct KeySignal {
  std::string x, y, y_minus;  ///< base column names; y_minus is subtracted from y when set
  double factor = 1;
  std::string xlabel, ylabel, what;
};

using FigureFunction = std::function<std::vector<Figure>(const RunData&)>;
using KeySignalFunction = std::function<std::optional<KeySignal>(const RunData&)>;

// ---------------------------------------------------------------------------------------- building blocks

/// "quantity [unit]", or just the quantity for dimensionless ("-" or no unit) signals.
std::string axisLabel(const std::string& quantity, const std::string& unit);
/// Multiplot grid of n panels: up to max_cols columns.
void grid(Figure& f, size_t n, size_t max_cols = 3);
/// A signal scaled into a readable unit: m → mm/µm, rad → mrad/µrad when the values are small.
struct Scaled {
  double factor = 1;
  std::string unit;
};
Scaled readableUnit(const std::string& unit, double max_abs);
/// y = column c (times `factor`) against time.
Series timeSeries(const RunData& run, int c, const std::string& title, double factor = 1,
                  LineStyle style = LineStyle::Line);
/// y = column c against column x.
Series xySeries(const RunData& run, int x, int c, const std::string& title, LineStyle style = LineStyle::Line);
/// A time panel of the given columns (legend: `legend(name)` or the names); y label from `quantity` and the
/// first column's unit.
Panel timePanel(const RunData& run, const std::vector<int>& cols, const std::string& title, const std::string& quantity,
                const std::function<std::string(const std::string&)>& legend = {});
/// Every column against time, six panels per page (any run gets these figures).
std::vector<Figure> genericFigures(const RunData& run);
/// The first column against time (the fallback key signal).
std::optional<KeySignal> timeKeySignal(const RunData& run, int c, const std::string& what);
/// Joint names of the columns `<prefix><joint>` (in file order).
std::vector<std::string> jointsWithPrefix(const RunData& run, const std::string& prefix);
bool startsWith(const std::string& s, const std::string& prefix);
bool endsWith(const std::string& s, const std::string& suffix);
std::string stripPrefix(const std::string& s, const std::string& prefix);

}  // namespace jointsim::experiments
