#pragma once
// Keeps Ceres's own log (glog: "Covariance matrix is near rank deficient", "Logging before
// InitGoogleLogging()") off the host's stderr while a fit runs: every failure Ceres reports is turned into
// a jointsim message (UnidentifiableError, InputError) by the fits themselves. Saves and restores glog's
// minimum level, so a host that configured glog keeps its setting. Not thread-safe (glog's flag is global).
#include <glog/logging.h>

namespace jointsim::identify {

class QuietCeres {
 public:
  QuietCeres() : saved_(FLAGS_minloglevel) { FLAGS_minloglevel = google::GLOG_FATAL; }
  ~QuietCeres() { FLAGS_minloglevel = saved_; }
  QuietCeres(const QuietCeres&) = delete;
  QuietCeres& operator=(const QuietCeres&) = delete;

 private:
  int saved_;
};

}  // namespace jointsim::identify
