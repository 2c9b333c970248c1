#include "jointsim/control/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "common/constants.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/io/csv_reader.hpp"

namespace jointsim::control {
namespace {

std::string trajectoryNum(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

bool allFinite(const Eigen::VectorXd& v) { return v.allFinite(); }

}  // namespace

JointSetpoint JointTrajectory::setpoint(double t) const {
  JointSetpoint s;
  s.q.resize(dof());
  s.qd.resize(dof());
  s.qdd.resize(dof());
  evaluate(t, s.q, s.qd, s.qdd);
  return s;
}

// ------------------------------------------------------------------------------------------ limits

void checkLimits(const JointTrajectory& trajectory, const std::vector<std::string>& joint_names,
                 const std::vector<multibody::JointLimits>& limits) {
  const int n = trajectory.dof();
  if (joint_names.size() != static_cast<size_t>(n) || limits.size() != static_cast<size_t>(n))
    throw InputError("checkLimits: the trajectory has " + std::to_string(n) + " joints but " +
                     std::to_string(joint_names.size()) + " joint names and " + std::to_string(limits.size()) +
                     " limits were given");
  const double T = std::max(0.0, trajectory.duration());
  if (!std::isfinite(T))
    throw InputError("the trajectory lasts " + trajectoryNum(T) + " s: expected a finite duration");
  const double step = std::max(1e-3, T / 1e7);
  std::vector<double> times;
  const auto count = static_cast<size_t>(std::floor(T / step));
  times.reserve(count + 2);
  for (size_t k = 0; k <= count; ++k) times.push_back(static_cast<double>(k) * step);
  times.push_back(T);
  for (double b : trajectory.breakpoints())
    if (b >= 0.0 && b <= T) times.push_back(b);
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());

  constexpr double kTol = 1e-9;
  Eigen::VectorXd q(n), qd(n), qdd(n);
  for (double t : times) {
    trajectory.evaluate(t, q, qd, qdd);
    for (int i = 0; i < n; ++i) {
      const auto& L = limits[static_cast<size_t>(i)];
      if (!(q[i] >= L.lower - kTol && q[i] <= L.upper + kTol))
        throw InputError("trajectory leaves the limits of joint " + joint_names[static_cast<size_t>(i)] +
                         " at t = " + trajectoryNum(t) + " s: q = " + trajectoryNum(q[i]) + " rad outside [" +
                         trajectoryNum(L.lower) + ", " + trajectoryNum(L.upper) + "]");
      if (std::isfinite(L.velocity) && !(std::abs(qd[i]) <= L.velocity + kTol))
        throw InputError("trajectory exceeds the velocity limit of joint " + joint_names[static_cast<size_t>(i)] +
                         " at t = " + trajectoryNum(t) + " s: |qd| = " + trajectoryNum(std::abs(qd[i])) + " rad/s > " +
                         trajectoryNum(L.velocity) + " rad/s");
    }
  }
}

// ------------------------------------------------------------------------------------------ point to point

PointToPointTrajectory::PointToPointTrajectory(Eigen::VectorXd start, std::vector<PtpSegment> segments)
    : start_(std::move(start)), spec_(std::move(segments)) {
  const Eigen::Index n = start_.size();
  if (n < 1) throw InputError("point_to_point: the start position needs at least one joint");
  if (!allFinite(start_)) throw InputError("point_to_point: the start position must be finite");
  double t = 0.0;
  Eigen::VectorXd from = start_;
  for (size_t k = 0; k < spec_.size(); ++k) {
    const PtpSegment& s = spec_[k];
    const std::string where = "point_to_point segment " + std::to_string(k) + ": ";
    if (s.target.size() != n)
      throw InputError(where + "target has " + std::to_string(s.target.size()) + " joint positions, expected " +
                       std::to_string(n));
    if (!allFinite(s.target)) throw InputError(where + "target must be finite");
    if (!(s.dwell >= 0.0 && std::isfinite(s.dwell))) throw InputError(where + "dwell must be >= 0 s");
    if (!(s.duration >= 0.0 && std::isfinite(s.duration))) throw InputError(where + "duration must be >= 0 s");
    if (!(s.acceleration >= 0.0 && std::isfinite(s.acceleration)))
      throw InputError(where + "acceleration must be > 0 rad/s^2");
    Seg g;
    g.t0 = t;
    g.from = from;
    g.to = s.target;
    g.delta = g.to - g.from;
    const double D = g.delta.cwiseAbs().maxCoeff();
    if (!std::isfinite(D)) throw InputError(where + "the move from the previous position is not a finite angle");
    if (s.duration > 0.0) {
      if (s.velocity != 0.0) throw InputError(where + "give either velocity (with acceleration) or duration, not both");
      const double T = s.duration;
      if (s.acceleration > 0.0 && D > 0.0) {
        const double disc = T * T - 4.0 * D / s.acceleration;
        if (disc < 0.0)
          throw InputError(where + "acceleration " + trajectoryNum(s.acceleration) + " rad/s^2 is too low to move " +
                           trajectoryNum(D) + " rad in " + trajectoryNum(T) +
                           " s (needs at least 4 D / T^2 = " + trajectoryNum(4.0 * D / (T * T)) + " rad/s^2)");
        g.ta = 0.5 * (T - std::sqrt(disc));
      } else {
        g.ta = 0.5 * T;
      }
      if (!(g.ta > 0.0)) g.ta = 0.5 * T;
      g.tc = std::max(0.0, T - 2.0 * g.ta);
    } else {
      if (!(s.velocity > 0.0 && std::isfinite(s.velocity))) throw InputError(where + "velocity must be > 0 rad/s");
      if (!(s.acceleration > 0.0)) throw InputError(where + "acceleration must be > 0 rad/s^2");
      const double v = s.velocity, a = s.acceleration;
      if (D == 0.0) {
        g.ta = g.tc = 0.0;
      } else if (D * a >= v * v) {
        g.ta = v / a;
        g.tc = std::max(0.0, D / v - v / a);
      } else {
        g.ta = std::sqrt(D / a);
        g.tc = 0.0;
      }
    }
    g.T = 2.0 * g.ta + g.tc;
    if (g.T > 0.0) {
      g.V = 1.0 / (g.ta + g.tc);
      g.A = g.V / g.ta;
    }
    if (!std::isfinite(t + g.T + s.dwell) || !std::isfinite(g.V) || !std::isfinite(g.A))
      throw InputError(where + "the move takes " + trajectoryNum(g.T) + " s with an acceleration phase of " +
                       trajectoryNum(g.ta) + " s: velocity, acceleration or duration out of any usable range");
    t += g.T + s.dwell;
    from = g.to;
    starts_.push_back(g.t0);
    segs_.push_back(std::move(g));
  }
  duration_ = t;
}

double PointToPointTrajectory::segmentEnd(int k) const {
  const Seg& g = segs_.at(static_cast<size_t>(k));
  return g.t0 + g.T;
}

void PointToPointTrajectory::evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                                      Eigen::Ref<Eigen::VectorXd> qdd) const {
  if (segs_.empty() || t < 0.0) {
    q = start_;
    qd.setZero();
    qdd.setZero();
    return;
  }
  const auto it = std::upper_bound(starts_.begin(), starts_.end(), t);
  const size_t k = it == starts_.begin() ? 0 : static_cast<size_t>(it - starts_.begin()) - 1;
  const Seg& g = segs_[k];
  const double tau = t - g.t0;
  if (tau >= g.T) {
    q = g.to;
    qd.setZero();
    qdd.setZero();
    return;
  }
  if (tau < g.ta) {  // acceleration
    q = g.from + (0.5 * g.A * tau * tau) * g.delta;
    qd = (g.A * tau) * g.delta;
    qdd = g.A * g.delta;
  } else if (tau < g.ta + g.tc) {  // cruise
    q = g.from + (0.5 * g.A * g.ta * g.ta + g.V * (tau - g.ta)) * g.delta;
    qd = g.V * g.delta;
    qdd.setZero();
  } else {  // deceleration, measured back from the end so the target is reached exactly
    const double u = g.T - tau;
    q = g.to - (0.5 * g.A * u * u) * g.delta;
    qd = (g.A * u) * g.delta;
    qdd = -g.A * g.delta;
  }
}

std::vector<double> PointToPointTrajectory::breakpoints() const {
  std::vector<double> out;
  for (const Seg& g : segs_) {
    if (!(g.T > 0.0) || g.delta.isZero(0.0)) continue;
    out.push_back(g.t0);
    out.push_back(g.t0 + g.ta);
    if (g.tc > 0.0) out.push_back(g.t0 + g.ta + g.tc);
    out.push_back(g.t0 + g.T);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  out.erase(std::remove_if(out.begin(), out.end(), [](double x) { return !(x > 0.0); }), out.end());
  return out;
}

std::string PointToPointTrajectory::describe() const {
  std::ostringstream os;
  os << "point_to_point(" << dof() << " joints, " << segs_.size() << " segments, duration " << duration_ << " s)";
  return os.str();
}

// ------------------------------------------------------------------------------------------ Fourier

FourierTrajectory::FourierTrajectory(FourierParams params) : p_(std::move(params)) {
  const Eigen::Index n = p_.offset.size();
  if (n < 1) throw InputError("fourier: the offset needs at least one joint");
  if (!(p_.base_frequency > 0.0 && std::isfinite(p_.base_frequency)))
    throw InputError("fourier: base_frequency must be > 0 Hz");
  if (p_.a.rows() != n || p_.b.rows() != n || p_.a.cols() != p_.b.cols() || p_.a.cols() < 1)
    throw InputError("fourier: a and b must both be " + std::to_string(n) + " x N (N >= 1 harmonics), got " +
                     std::to_string(p_.a.rows()) + " x " + std::to_string(p_.a.cols()) + " and " +
                     std::to_string(p_.b.rows()) + " x " + std::to_string(p_.b.cols()));
  if (!p_.offset.allFinite() || !p_.a.allFinite() || !p_.b.allFinite())
    throw InputError("fourier: offset and coefficients must be finite");
  if (!(p_.fade_in >= 0.0 && std::isfinite(p_.fade_in))) throw InputError("fourier: fade_in must be >= 0 s");
  if (p_.duration == 0.0) p_.duration = p_.fade_in + 1.0 / p_.base_frequency;
  if (!(p_.duration > 0.0 && std::isfinite(p_.duration)) || p_.duration < p_.fade_in)
    throw InputError("fourier: duration must be > 0 s and >= fade_in (" + trajectoryNum(p_.fade_in) + " s)");
}

void FourierTrajectory::evaluateSeries(double tau, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                                       Eigen::Ref<Eigen::VectorXd> qdd) const {
  const double wf = kTwoPi * p_.base_frequency;
  q = p_.offset;
  qd.setZero();
  qdd.setZero();
  for (Eigen::Index k = 0; k < p_.a.cols(); ++k) {
    const double wk = wf * static_cast<double>(k + 1);
    const double s = std::sin(wk * tau), c = std::cos(wk * tau);
    for (Eigen::Index i = 0; i < q.size(); ++i) {
      const double a = p_.a(i, k), b = p_.b(i, k);
      q[i] += (a * s - b * c) / wk;
      qd[i] += a * c + b * s;
      qdd[i] += wk * (b * c - a * s);
    }
  }
}

void FourierTrajectory::evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                                 Eigen::Ref<Eigen::VectorXd> qdd) const {
  const double T = p_.fade_in;
  if (T > 0.0 && t <= 0.0) {
    q = p_.offset;
    qd.setZero();
    qdd.setZero();
    return;
  }
  evaluateSeries(t - T, q, qd, qdd);
  if (T > 0.0 && t < T) {
    // q = q0 + w F, qd = w' F + w F', qdd = w'' F + 2 w' F' + w F'' with F = q_F (series minus offset).
    const double s = t / T, s1 = 1.0 - s;
    const double w = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
    const double w1 = 30.0 * s * s * s1 * s1 / T;
    const double w2 = 60.0 * s * s1 * (1.0 - 2.0 * s) / (T * T);
    for (Eigen::Index i = 0; i < q.size(); ++i) {
      const double F = q[i] - p_.offset[i], F1 = qd[i], F2 = qdd[i];
      q[i] = p_.offset[i] + w * F;
      qd[i] = w1 * F + w * F1;
      qdd[i] = w2 * F + 2.0 * w1 * F1 + w * F2;
    }
  }
}

std::string FourierTrajectory::describe() const {
  std::ostringstream os;
  os << "fourier(" << dof() << " joints, " << harmonics() << " harmonics, base_frequency " << p_.base_frequency
     << " Hz, fade_in " << p_.fade_in << " s, duration " << p_.duration << " s)";
  return os.str();
}

// ------------------------------------------------------------------------------------------ sampled

SampledTrajectory::SampledTrajectory(std::vector<double> times, Eigen::MatrixXd positions, std::string source)
    : t_(std::move(times)), y_(std::move(positions)), source_(std::move(source)) {
  const size_t K = t_.size();
  if (K < 2) throw InputError(source_ + ": a sampled trajectory needs at least 2 samples, got " + std::to_string(K));
  if (y_.rows() < 1 || static_cast<size_t>(y_.cols()) != K)
    throw InputError(source_ + ": positions must be n x " + std::to_string(K) + " (one column per sample), got " +
                     std::to_string(y_.rows()) + " x " + std::to_string(y_.cols()));
  if (!y_.allFinite()) throw InputError(source_ + ": positions must be finite");
  for (size_t k = 0; k < K; ++k) {
    if (!std::isfinite(t_[k])) throw InputError(source_ + ": sample " + std::to_string(k) + ": time must be finite");
    if (k > 0 && !(t_[k] > t_[k - 1]))
      throw InputError(source_ + ": sample " + std::to_string(k) + ": time must increase strictly");
  }
  t_start_ = t_[0];
  for (double& t : t_) t -= t_start_;
  t_[0] = 0.0;

  // Natural cubic spline: second derivatives M with M_0 = M_{K-1} = 0 and, for 0 < j < K-1,
  // h_{j-1} M_{j-1} + 2 (h_{j-1} + h_j) M_j + h_j M_{j+1} = 6 (Δy_j / h_j − Δy_{j-1} / h_{j-1}).
  // Thomas algorithm on all joints at once.
  const Eigen::Index n = y_.rows();
  m_ = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(K));
  if (K > 2) {
    std::vector<double> cprime(K, 0.0);
    Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(K));
    for (size_t j = 1; j + 1 < K; ++j) {
      const double h0 = t_[j] - t_[j - 1], h1 = t_[j + 1] - t_[j];
      const auto J = static_cast<Eigen::Index>(j);
      const Eigen::VectorXd rhs = 6.0 * ((y_.col(J + 1) - y_.col(J)) / h1 - (y_.col(J) - y_.col(J - 1)) / h0);
      const double lower = (j == 1) ? 0.0 : h0;  // M_0 = 0 is known
      const double denom = 2.0 * (h0 + h1) - lower * cprime[j - 1];
      cprime[j] = (j + 2 < K) ? h1 / denom : 0.0;  // M_{K-1} = 0 is known
      d.col(J) = (rhs - lower * d.col(J - 1)) / denom;
    }
    for (size_t j = K - 2; j >= 1; --j) {
      const auto J = static_cast<Eigen::Index>(j);
      m_.col(J) = d.col(J) - cprime[j] * m_.col(J + 1);
    }
  }
}

void SampledTrajectory::evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                                 Eigen::Ref<Eigen::VectorXd> qdd) const {
  const Eigen::Index last = y_.cols() - 1;
  if (t < 0.0 || t >= t_.back()) {
    q = t < 0.0 ? y_.col(0) : y_.col(last);
    qd.setZero();
    qdd.setZero();
    return;
  }
  const auto it = std::upper_bound(t_.begin(), t_.end(), t);
  auto k = static_cast<Eigen::Index>(it - t_.begin()) - 1;
  k = std::clamp<Eigen::Index>(k, 0, last - 1);
  const double h = t_[static_cast<size_t>(k + 1)] - t_[static_cast<size_t>(k)];
  const double A = (t_[static_cast<size_t>(k + 1)] - t) / h, B = 1.0 - A;
  q = A * y_.col(k) + B * y_.col(k + 1) + ((A * A * A - A) * h * h / 6.0) * m_.col(k) +
      ((B * B * B - B) * h * h / 6.0) * m_.col(k + 1);
  qd = (y_.col(k + 1) - y_.col(k)) / h - ((3.0 * A * A - 1.0) * h / 6.0) * m_.col(k) +
       ((3.0 * B * B - 1.0) * h / 6.0) * m_.col(k + 1);
  qdd = A * m_.col(k) + B * m_.col(k + 1);
}

std::string SampledTrajectory::describe() const {
  std::ostringstream os;
  os << "csv(" << source_ << ", " << dof() << " joints, " << t_.size() << " samples, duration " << t_.back() << " s)";
  return os.str();
}

SampledTrajectory SampledTrajectory::fromCsv(const std::string& path, int dof, const std::vector<std::string>& columns,
                                             double gap_factor) {
  if (dof < 1) throw InputError(path + ": the number of joints must be >= 1");
  if (!(gap_factor == 0.0 || (gap_factor > 1.0 && std::isfinite(gap_factor))))
    throw InputError(path + ": gap_factor must be > 1 (or 0 to disable the gap check), got " +
                     trajectoryNum(gap_factor));
  if (!columns.empty() && columns.size() != static_cast<size_t>(dof))
    throw InputError(path + ": " + std::to_string(columns.size()) + " column names given for " + std::to_string(dof) +
                     " joints");
  const io::CsvTable table = io::readCsv(path);
  const std::vector<std::string>& header = table.header;
  std::vector<size_t> cols;
  if (columns.empty()) {
    if (header.size() != static_cast<size_t>(dof) + 1)
      throw InputError(path + ":1: expected 1 + " + std::to_string(dof) + " = " + std::to_string(dof + 1) +
                       " columns (time, then one per joint), got " + std::to_string(header.size()) +
                       "; name the joint columns with `columns` to select them");
    for (int i = 1; i <= dof; ++i) cols.push_back(static_cast<size_t>(i));
  } else {
    for (const std::string& name : columns) {
      const auto it = std::find(header.begin(), header.end(), name);
      if (it == header.end())
        throw InputError(path + ":1: no column named '" + name + "' (columns: " + join(header, ", ") + ")");
      if (it == header.begin()) throw InputError(path + ":1: column '" + name + "' is the time column");
      cols.push_back(static_cast<size_t>(it - header.begin()));
    }
  }
  const std::vector<double> times = io::checkedTimes(table, 0, gap_factor, [&](Eigen::Index r) {
    return path + ":" + std::to_string(table.lines[static_cast<size_t>(r)]);
  });
  std::vector<double> values;  // row-major, dof per sample
  for (Eigen::Index r = 0; r < table.rows(); ++r)
    for (size_t c : cols) values.push_back(table.data(r, static_cast<Eigen::Index>(c)));

  Eigen::MatrixXd y(dof, static_cast<Eigen::Index>(times.size()));
  for (size_t k = 0; k < times.size(); ++k)
    for (int i = 0; i < dof; ++i)
      y(i, static_cast<Eigen::Index>(k)) = values[k * static_cast<size_t>(dof) + static_cast<size_t>(i)];
  return SampledTrajectory(std::move(times), std::move(y), path);
}

// ---------------------------------------------------------------------------------------------------

LogColumns LogColumns::urRtde(int dof) {
  LogColumns c;
  c.time = "timestamp";
  c.q = expand("target_q_{i}", dof, "q");
  c.qd = expand("target_qd_{i}", dof, "qd");
  c.qdd = expand("target_qdd_{i}", dof, "qdd");
  c.q_measured = expand("actual_q_{i}", dof, "q_measured");
  return c;
}

std::vector<std::string> LogColumns::expand(const std::string& pattern, int dof, const std::string& what) {
  const bool one = pattern.find("{j}") != std::string::npos, zero = pattern.find("{i}") != std::string::npos;
  if (one == zero)
    throw InputError(what + ": expected a column-name pattern with {j} (joint 1..n) or {i} (index 0..n-1), got '" +
                     pattern + "'");
  std::vector<std::string> out;
  for (int k = 0; k < dof; ++k) {
    std::string name = pattern;
    const std::string key = one ? "{j}" : "{i}", num = std::to_string(one ? k + 1 : k);
    for (size_t p = name.find(key); p != std::string::npos; p = name.find(key, p + num.size()))
      name.replace(p, key.size(), num);
    out.push_back(name);
  }
  return out;
}

LoggedTrajectory::LoggedTrajectory(std::vector<double> times, Eigen::MatrixXd q, Eigen::MatrixXd qd,
                                   Eigen::MatrixXd qdd, double start, std::string source, bool from_derivatives,
                                   double rest_speed)
    : t_(std::move(times)),
      q_(std::move(q)),
      qd_(std::move(qd)),
      qdd_(std::move(qdd)),
      start_(start),
      source_(std::move(source)),
      rest_speed_(rest_speed) {
  const auto K = static_cast<Eigen::Index>(t_.size());
  if (K < 2) throw InputError(source_ + ": a logged trajectory needs at least 2 samples, got " + std::to_string(K));
  auto shape = [&](const Eigen::MatrixXd& m, const char* what) {
    if (m.rows() != q_.rows() || m.cols() != K || q_.rows() < 1)
      throw InputError(source_ + ": " + what + " must be n x " + std::to_string(K) + " (one column per sample), got " +
                       std::to_string(m.rows()) + " x " + std::to_string(m.cols()));
    if (!m.allFinite()) throw InputError(source_ + ": " + what + " must be finite");
  };
  shape(q_, "q");
  shape(qd_, "qd");
  if (qdd_.size() > 0) shape(qdd_, "qdd");
  for (size_t k = 0; k < t_.size(); ++k) {
    if (!std::isfinite(t_[k])) throw InputError(source_ + ": sample " + std::to_string(k) + ": time must be finite");
    if (k > 0 && !(t_[k] > t_[k - 1]))
      throw InputError(source_ + ": sample " + std::to_string(k) + ": time must increase strictly");
  }
  if (!(rest_speed_ >= 0.0) || !std::isfinite(rest_speed_))
    throw InputError(source_ + ": rest speed " + trajectoryNum(rest_speed_) + " rad/s: expected a speed >= 0");
  if (!(start_ >= t_.front() && start_ < t_.back()))
    throw InputError(source_ + ": start time " + trajectoryNum(start_) + " s is outside the log [" +
                     trajectoryNum(t_.front()) + ", " + trajectoryNum(t_.back()) + ") s");
  if (from_derivatives && qdd_.size() > 0) {
    rests_.resize(static_cast<size_t>(q_.rows()));
    for (Eigen::Index j = 0; j < q_.rows(); ++j) positionsFromDerivatives(j);
  }
}

void LoggedTrajectory::evaluate(double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd,
                                Eigen::Ref<Eigen::VectorXd> qdd) const {
  const double tl = std::max(t, 0.0) + start_;  // log time; before t = 0: rest at q(0)
  if (tl >= t_.back()) {
    q = q_.col(q_.cols() - 1);
    qd.setZero();
    qdd.setZero();
    return;
  }
  const auto it = std::upper_bound(t_.begin(), t_.end(), tl);
  const Eigen::Index k = std::clamp<Eigen::Index>(static_cast<Eigen::Index>(it - t_.begin()) - 1, 0, q_.cols() - 2);
  const double h = t_[static_cast<size_t>(k + 1)] - t_[static_cast<size_t>(k)];
  const double s = (tl - t_[static_cast<size_t>(k)]) / h;
  const bool quintic = qdd_.size() > 0;
  for (Eigen::Index j = 0; j < q_.rows(); ++j) {
    const double q0 = q_(j, k), q1 = q_(j, k + 1), v0 = h * qd_(j, k), v1 = h * qd_(j, k + 1);
    double c2 = 0.0, c3 = 0.0, c4 = 0.0, c5 = 0.0;  // q(s) = q0 + v0 s + c2 s² + ... (v in rad per interval)
    if (quintic) {
      const double a0 = h * h * qdd_(j, k), a1 = h * h * qdd_(j, k + 1);
      const double D = q1 - q0 - v0 - 0.5 * a0, V = v1 - v0 - a0, A = a1 - a0;
      c2 = 0.5 * a0;
      c3 = 10.0 * D - 4.0 * V + 0.5 * A;
      c4 = -15.0 * D + 7.0 * V - A;
      c5 = 6.0 * D - 3.0 * V + 0.5 * A;
    } else {  // cubic Hermite: q(s) = q0 + v0 s + (3Δq − 2v0 − v1) s² + (−2Δq + v0 + v1) s³
      const double dq = q1 - q0;
      c2 = 3.0 * dq - 2.0 * v0 - v1;
      c3 = -2.0 * dq + v0 + v1;
    }
    q[j] = q0 + s * (v0 + s * (c2 + s * (c3 + s * (c4 + s * c5))));
    qd[j] = (v0 + s * (2.0 * c2 + s * (3.0 * c3 + s * (4.0 * c4 + s * 5.0 * c5)))) / h;
    qdd[j] = (2.0 * c2 + s * (6.0 * c3 + s * (12.0 * c4 + s * 20.0 * c5))) / (h * h);
  }
  if (t < 0.0) {
    qd.setZero();
    qdd.setZero();
  }
}

std::vector<double> LoggedTrajectory::breakpoints() const {
  std::vector<double> b;
  if (qdd_.size() == 0)  // cubic Hermite: q̈ jumps at every sample
    for (double t : t_)
      if (t > start_ && t < t_.back()) b.push_back(t - start_);
  b.push_back(t_.back() - start_);
  return b;
}

bool LoggedTrajectory::startPositions(Eigen::Ref<Eigen::VectorXd> q) const {
  if (measured_start_.size() == 0) return false;
  q = measured_start_;
  return true;
}

std::vector<std::vector<std::pair<double, double>>> LoggedTrajectory::rests() const {
  constexpr double inf = std::numeric_limits<double>::infinity();
  std::vector<std::vector<std::pair<double, double>>> out(rests_.size());
  const double end = t_.back();
  for (size_t j = 0; j < rests_.size(); ++j) {
    for (const auto& [a, b] : rests_[j]) {
      if (b < start_) continue;  // over before the replay starts
      // Before t = 0 the replay rests at q(0); after the last sample it holds the last position.
      out[j].emplace_back(a <= start_ ? -inf : a - start_, b >= end ? inf : b - start_);
    }
    if (out[j].empty() || std::isfinite(out[j].back().second)) out[j].emplace_back(end - start_, inf);
  }
  return out;
}

std::string LoggedTrajectory::describe() const {
  std::ostringstream os;
  os << "log(" << source_ << ", " << dof() << " joints, " << t_.size() << " samples, "
     << (qdd_.size() > 0 ? "quintic" : "cubic") << " Hermite, from " << start_ << " s, duration " << duration()
     << " s)";
  return os.str();
}

void LoggedTrajectory::positionsFromDerivatives(Eigen::Index j) {
  const Eigen::Index K = q_.cols();
  const Eigen::RowVectorXd logged = q_.row(j);
  auto time = [&](Eigen::Index k) { return t_[static_cast<size_t>(k)]; };
  // A sample rests when its speed is at most rest_speed and its acceleration could not take it beyond that within
  // one (mean) sample period; a resting sample's derivatives become exactly 0.
  const double a_rest = rest_speed_ * static_cast<double>(K - 1) / (time(K - 1) - time(0));
  std::vector<char> at_rest(static_cast<size_t>(K));
  for (Eigen::Index k = 0; k < K; ++k) {
    at_rest[static_cast<size_t>(k)] = std::abs(qd_(j, k)) <= rest_speed_ && std::abs(qdd_(j, k)) <= a_rest;
    if (at_rest[static_cast<size_t>(k)]) qd_(j, k) = qdd_(j, k) = 0.0;
  }
  auto rest = [&](Eigen::Index k) { return at_rest[static_cast<size_t>(k)] != 0; };
  for (Eigen::Index k = 0; k < K;) {
    if (rest(k)) {  // a rest k..m: hold the logged position the next move starts from
      Eigen::Index m = k;
      while (m + 1 < K && rest(m + 1)) ++m;
      for (Eigen::Index r = k; r <= m; ++r) q_(j, r) = logged[m];
      rests_[static_cast<size_t>(j)].emplace_back(time(k), time(m));
      k = m + 1;
      continue;
    }
    // A move from sample s (the last rest sample, or the first sample) to e (the first rest sample after it, or K).
    const Eigen::Index s = k == 0 ? 0 : k - 1;
    if (k == 0) q_(j, 0) = logged[0];
    Eigen::Index e = k;
    while (e < K && !rest(e)) ++e;
    const Eigen::Index last = std::min(e, K - 1);
    for (Eigen::Index i = s + 1; i <= last; ++i) {
      const double h = time(i) - time(i - 1);
      const double a0 = qdd_(j, i - 1), a1 = qdd_(j, i), v0 = qd_(j, i - 1), v1 = qd_(j, i);
      const bool jump = std::abs(v1 - v0 - 0.5 * h * (a0 + a1)) > h * std::max(std::abs(a0), std::abs(a1)) + 1e-4;
      q_(j, i) = jump ? logged[i] : q_(j, i - 1) + 0.5 * h * (v0 + v1) + h * h / 12.0 * (a0 - a1);
    }
    if (e < K) {  // meet the rest's held position: the mismatch E blended in over the move (w: quintic smoothstep)
      Eigen::Index m = e;
      while (m + 1 < K && rest(m + 1)) ++m;
      const double E = logged[m] - q_(j, e), T = time(e) - time(s);
      for (Eigen::Index i = s + 1; i < e; ++i) {
        const double u = (time(i) - time(s)) / T;
        q_(j, i) += E * u * u * u * (10.0 + u * (-15.0 + 6.0 * u));
        qd_(j, i) += E * u * u * (30.0 + u * (-60.0 + 30.0 * u)) / T;
        qdd_(j, i) += E * u * (60.0 + u * (-180.0 + 120.0 * u)) / (T * T);
      }
    }
    k = e;
  }
}

LoggedTrajectory LoggedTrajectory::fromCsv(const std::string& path, int dof, const LogColumns& columns, double start,
                                           double gap_factor, bool from_derivatives, double rest_speed) {
  if (dof < 1) throw InputError(path + ": the number of joints must be >= 1");
  if (!(gap_factor == 0.0 || (gap_factor > 1.0 && std::isfinite(gap_factor))))
    throw InputError(path + ": gap_factor must be > 1 (or 0 to disable the gap check), got " +
                     trajectoryNum(gap_factor));
  const io::CsvTable table = io::readCsv(path);
  const int tc = columns.time.empty() ? 0 : table.require(columns.time, "the log's time in s");
  auto pick = [&](const std::vector<std::string>& names, const char* what, bool optional) {
    std::vector<int> idx;
    if (names.empty() && optional) return idx;
    if (names.size() != static_cast<size_t>(dof))
      throw InputError(path + ": " + std::to_string(names.size()) + " " + what + " column names given for " +
                       std::to_string(dof) + " joints");
    for (const std::string& n : names) idx.push_back(table.require(n, what));
    return idx;
  };
  const std::vector<int> cq = pick(columns.q, "commanded positions in rad", false);
  const std::vector<int> cqd = pick(columns.qd, "commanded velocities in rad/s", false);
  const std::vector<int> cqdd = pick(columns.qdd, "commanded accelerations in rad/s^2", true);
  const std::vector<int> cm = pick(columns.q_measured, "measured positions in rad", true);
  const std::vector<double> times = io::checkedTimes(table, tc, gap_factor);
  const Eigen::Index K = table.rows();
  auto gather = [&](const std::vector<int>& idx) {
    Eigen::MatrixXd m(dof, idx.empty() ? 0 : K);
    for (size_t j = 0; j < idx.size(); ++j) m.row(static_cast<Eigen::Index>(j)) = table.data.col(idx[j]).transpose();
    return m;
  };
  const double t0 = start < 0.0 ? times.front() : start;
  if (!(t0 >= times.front() && t0 < times.back()))
    throw InputError(path + ": start time " + trajectoryNum(t0) + " s is outside the log's times [" +
                     trajectoryNum(times.front()) + ", " + trajectoryNum(times.back()) + ") s");
  LoggedTrajectory traj(times, gather(cq), gather(cqd), gather(cqdd), t0, path, from_derivatives, rest_speed);
  if (!cm.empty()) {  // the measured positions at the start, linear between the samples around it
    const Eigen::MatrixXd m = gather(cm);
    const auto it = std::upper_bound(times.begin(), times.end(), t0);
    const auto k = static_cast<Eigen::Index>(it - times.begin()) - 1;
    const double w =
        (t0 - times[static_cast<size_t>(k)]) / (times[static_cast<size_t>(k + 1)] - times[static_cast<size_t>(k)]);
    traj.setMeasuredStart((1.0 - w) * m.col(k) + w * m.col(k + 1));
  }
  return traj;
}

}  // namespace jointsim::control
