#pragma once
/// \file
/// Scalar time profiles used as inputs and references: constant, step, ramp, triangle, sine, piecewise
/// (linear or hold) and CSV time series (linear interpolation). value(t) is pure and allocation-free.
/// Units are those of the signal it drives (N·m, V, rad/s, ...); times in s.

#include <limits>
#include <string>
#include <vector>

namespace jointsim::control {

class Profile {
 public:
  enum class Kind { Constant, Step, Ramp, Triangle, Sine, Piecewise, Csv };

  static Profile constant(double value);
  /// `initial` before `time`, `final` from `time` on.
  static Profile step(double initial, double final_value, double time);
  /// offset until t0, then offset + slope (t − t0), held after t1 (t1 <= t0: never held).
  static Profile ramp(double offset, double slope, double t0 = 0.0, double t1 = -1.0);
  /// Symmetric triangle: offset + amplitude·tri(t/period), starting at offset and rising first
  /// (0 → +A at T/4 → −A at 3T/4 → 0 at T).
  static Profile triangle(double amplitude, double period, double offset = 0.0);
  /// offset + amplitude sin(2π f t + phase) for t < until, 0 from `until` on (a sine switched off by a
  /// step, as in the MSL Friction example); until = +inf: never switched off.
  static Profile sine(double amplitude, double frequency, double phase = 0.0, double offset = 0.0,
                      double until = std::numeric_limits<double>::infinity());
  /// Through the points (times[k], values[k]) (times strictly increasing), linear or held, constant
  /// outside the range.
  static Profile piecewise(std::vector<double> times, std::vector<double> values, bool hold = false);
  /// Loads a CSV file with a header line and at least two columns; `column` names the value column
  /// (empty: the second). The first column is time [s]. Throws InputError naming the file and line.
  static Profile csv(const std::string& path, const std::string& column = "");

  double value(double t) const;
  Kind kind() const { return kind_; }
  /// Times at which the profile or its slope jumps (for solver restarts), within [0, horizon].
  std::vector<double> breakpoints(double horizon) const;
  /// One-line description for summaries, e.g. "triangle(amplitude=3, period=40, offset=0)".
  std::string describe() const;

 private:
  Kind kind_ = Kind::Constant;
  double a_ = 0, b_ = 0, c_ = 0, d_ = 0;  // meaning depends on kind (see the factories)
  double until_ = std::numeric_limits<double>::infinity();
  std::vector<double> times_, values_;
  bool hold_ = false;
  std::string source_;
};

}  // namespace jointsim::control
