#include "jointsim/control/profile.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "common/constants.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/interpolate.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/io/csv_reader.hpp"

namespace jointsim::control {
namespace {

void requireFinite(double v, const char* what) {
  if (!std::isfinite(v)) throw InputError(std::string("profile: ") + what + " must be finite");
}
}  // namespace

Profile Profile::constant(double value) {
  requireFinite(value, "value");
  Profile p;
  p.kind_ = Kind::Constant;
  p.a_ = value;
  return p;
}

Profile Profile::step(double initial, double final_value, double time) {
  requireFinite(initial, "initial");
  requireFinite(final_value, "final");
  requireFinite(time, "time");
  Profile p;
  p.kind_ = Kind::Step;
  p.a_ = initial;
  p.b_ = final_value;
  p.c_ = time;
  return p;
}

Profile Profile::ramp(double offset, double slope, double t0, double t1) {
  requireFinite(offset, "offset");
  requireFinite(slope, "slope");
  Profile p;
  p.kind_ = Kind::Ramp;
  p.a_ = offset;
  p.b_ = slope;
  p.c_ = t0;
  p.d_ = t1;
  return p;
}

Profile Profile::triangle(double amplitude, double period, double offset) {
  if (!(period > 0.0)) throw InputError("profile: triangle period must be > 0 s");
  requireFinite(amplitude, "amplitude");
  Profile p;
  p.kind_ = Kind::Triangle;
  p.a_ = amplitude;
  p.b_ = period;
  p.c_ = offset;
  return p;
}

Profile Profile::sine(double amplitude, double frequency, double phase, double offset, double until) {
  requireFinite(amplitude, "amplitude");
  if (!(frequency >= 0.0)) throw InputError("profile: sine frequency must be >= 0 Hz");
  Profile p;
  p.kind_ = Kind::Sine;
  p.a_ = amplitude;
  p.b_ = frequency;
  p.c_ = phase;
  p.d_ = offset;
  p.until_ = until;
  return p;
}

Profile Profile::piecewise(std::vector<double> times, std::vector<double> values, bool hold) {
  if (times.empty() || times.size() != values.size())
    throw InputError("profile: piecewise needs as many times as values (at least one)");
  for (size_t k = 0; k < times.size(); ++k) {
    requireFinite(times[k], "time");
    requireFinite(values[k], "value");
    if (k > 0 && !(times[k] > times[k - 1]))
      throw InputError("profile: piecewise times must be strictly increasing (entry " + std::to_string(k) + ")");
  }
  Profile p;
  p.kind_ = Kind::Piecewise;
  p.times_ = std::move(times);
  p.values_ = std::move(values);
  p.hold_ = hold;
  return p;
}

Profile Profile::csv(const std::string& path, const std::string& column) {
  const io::CsvTable table = io::readCsv(path);
  if (table.header.size() < 2) throw InputError(path + ":1: expected at least two columns (time and value)");
  int col = 1;
  if (!column.empty()) {
    col = table.find(column);
    if (col < 0)
      throw InputError(path + ":1: no column named '" + column + "' (columns: " + join(table.header, ", ") + ")");
  }
  std::vector<double> t, v;
  for (Eigen::Index r = 0; r < table.rows(); ++r) {
    if (!t.empty() && !(table.data(r, 0) > t.back()))
      throw InputError(table.where(r, 0) + ": time must increase strictly");
    t.push_back(table.data(r, 0));
    v.push_back(table.data(r, col));
  }
  if (t.empty()) throw InputError(path + ": no data rows");
  Profile p = piecewise(std::move(t), std::move(v), false);
  p.kind_ = Kind::Csv;
  p.source_ = path + (column.empty() ? "" : ":" + column);
  return p;
}

double Profile::value(double t) const {
  switch (kind_) {
    case Kind::Constant: return a_;
    case Kind::Step: return t < c_ ? a_ : b_;
    case Kind::Ramp: {
      if (t <= c_) return a_;
      const double tt = (d_ > c_) ? std::min(t, d_) : t;
      return a_ + b_ * (tt - c_);
    }
    case Kind::Triangle: {
      double phase = std::fmod(t / b_, 1.0);
      if (phase < 0) phase += 1.0;
      const double tri = phase < 0.25 ? 4 * phase : (phase < 0.75 ? 2 - 4 * phase : 4 * phase - 4);
      return c_ + a_ * tri;
    }
    case Kind::Sine: return t < until_ ? d_ + a_ * std::sin(kTwoPi * b_ * t + c_) : 0.0;
    case Kind::Piecewise:
    case Kind::Csv: {
      if (hold_) {
        if (t <= times_.front()) return values_.front();
        if (t >= times_.back()) return values_.back();
        const auto it = std::upper_bound(times_.begin(), times_.end(), t);
        return values_[static_cast<size_t>(it - times_.begin()) - 1];
      }
      return interpolateLinear(
          times_.size(), [this](size_t i) { return times_[i]; }, [this](size_t i) { return values_[i]; }, t,
          Ends::Hold);
    }
  }
  return 0.0;
}

std::vector<double> Profile::breakpoints(double horizon) const {
  std::vector<double> out;
  auto add = [&](double t) {
    if (t > 0.0 && t < horizon) out.push_back(t);
  };
  switch (kind_) {
    case Kind::Step: add(c_); break;
    case Kind::Ramp:
      add(c_);
      if (d_ > c_) add(d_);
      break;
    case Kind::Triangle:
      for (double t = 0.25 * b_; t < horizon; t += 0.5 * b_) add(t);
      break;
    case Kind::Piecewise:
    case Kind::Csv:
      if (hold_ || kind_ == Kind::Piecewise)
        for (double t : times_) add(t);
      break;
    case Kind::Sine: add(until_); break;
    default: break;
  }
  return out;
}

std::string Profile::describe() const {
  std::ostringstream os;
  switch (kind_) {
    case Kind::Constant: os << "constant(value=" << a_ << ")"; break;
    case Kind::Step: os << "step(initial=" << a_ << ", final=" << b_ << ", time=" << c_ << ")"; break;
    case Kind::Ramp: os << "ramp(offset=" << a_ << ", slope=" << b_ << ", t0=" << c_ << ", t1=" << d_ << ")"; break;
    case Kind::Triangle: os << "triangle(amplitude=" << a_ << ", period=" << b_ << ", offset=" << c_ << ")"; break;
    case Kind::Sine:
      os << "sine(amplitude=" << a_ << ", frequency=" << b_ << ", phase=" << c_ << ", offset=" << d_ << ")";
      break;
    case Kind::Piecewise: os << "piecewise(" << times_.size() << " points" << (hold_ ? ", hold" : "") << ")"; break;
    case Kind::Csv: os << "csv(" << source_ << ", " << times_.size() << " rows)"; break;
  }
  return os.str();
}

}  // namespace jointsim::control
