#pragma once
/// \file
/// `ClampingPathPlanning` of [Olsson2017, §3.11, Table 3.8, A.14] (timings derived): a chain of
/// [MSL, Blocks.Sources.KinematicPTP2] segments that swing one axis reference back and forth,
/// 0 → +q_pos → −q_pos → +q_pos → … . Segment k (0-based) starts at k·segment_time and is active on
/// [k·T, (k+1)·T); a segment that has not finished by the end of its slot is cut off there (the reference then
/// jumps, as in `path2` of [Olsson2017]; derived from [Olsson2017, A.14] and Listing 4.1).
/// After the last slot the reference holds the last segment's end point with zero speed.
/// The default (five 3 s segments) is that of [Olsson2017]; the path of one axis is independent of the
/// others.

#include <vector>

#include "jointsim/control/kinematic_ptp.hpp"

namespace jointsim::control {

struct ClampingPathParams {
  double q_pos = 0.157079632679;  ///< swing amplitude [rad] (arm side); 0 = hold the start angle
  double qd_max = 0.2;            ///< speed limit [rad/s], > 0
  double qdd_max = 0.5;           ///< acceleration limit [rad/s²], > 0
  double segment_time = 3.0;      ///< slot length of each segment [s], > 0
  int segments = 5;               ///< number of segments ([Olsson2017]: 5), >= 1
  void validate() const;          ///< throws InputError
};

class ClampingPath {
 public:
  explicit ClampingPath(const ClampingPathParams& params);
  /// Reference angle [rad], speed [rad/s] and acceleration [rad/s²] at time t [s] (relative to the start).
  void evaluate(double t, double& q, double& qd, double& qdd) const;
  /// Times [s] at which the reference or its derivatives are discontinuous (segment slots and phase
  /// switches), sorted, for integrator restarts.
  std::vector<double> breakpoints() const;
  /// End of the last slot [s].
  double endTime() const { return p_.segment_time * p_.segments; }
  const ClampingPathParams& params() const { return p_; }

 private:
  ClampingPathParams p_;
  std::vector<KinematicPtpTrajectory> segs_;
  double final_ = 0.0;
};

}  // namespace jointsim::control
