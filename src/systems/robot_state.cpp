// RobotSystem (robot_system.hpp): the run state as bytes (sim::PlantState::save/load), checked on reading as the
// setters check their arguments.
#include <cmath>
#include <cstdint>
#include <locale>
#include <random>
#include <sstream>
#include <string>

#include "jointsim/common/bytes.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/systems/robot_system.hpp"

namespace jointsim::systems {

namespace {
/// The noise generator's state as text (the standard library's portable textual form).
template <class T>
std::string streamed(const T& x) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << x;
  return out.str();
}
template <class T>
bool unstreamed(const std::string& text, T& x) {
  std::istringstream in(text);
  in.imbue(std::locale::classic());
  in >> x;
  return !in.fail();
}
}  // namespace

void RobotSystem::State::save(ByteWriter& out) const {
  const int n = static_cast<int>(port.size());
  out.tag("robot inputs");
  for (int k = 0; k < n; ++k) {
    out.u64(static_cast<std::uint64_t>(port[static_cast<size_t>(k)]));
    out.u64(static_cast<std::uint64_t>(applied_port[static_cast<size_t>(k)]));
  }
  out.vector(cmd);
  out.vector(applied_cmd);
  out.flags(ref_held);
  out.vector(ref_q);
  out.vector(ref_qd);
  out.vector(ref_qdd);
  out.vector(q_start);
  out.u64(user_wrenches.size());
  for (const auto& [f, w] : user_wrenches) {
    out.i64(f);
    out.vector(w);
  }
  out.tag("sampled control");
  out.doubles(ctrl_x);
  out.vector(held_u);
  out.vector(held_i_ref);
  out.vector(held_q_fb);
  out.vector(prev_qm_meas);
  out.boolean(first_sample);
  out.i64(inner_count);
  out.text(streamed(engine));
  out.text(streamed(normal));
  out.tag("faults");
  out.doubles(fault_applied);
  out.u64(stuck_episode.size());
  for (long e : stuck_episode) out.i64(e);
  out.doubles(stuck_value);
  out.tag("relative replay");
  out.vector(anchor);
  out.tag("load torques");
  loads.save(out);
}

void RobotSystem::State::load(ByteReader& in) {
  const auto& robot = static_cast<const RobotSystem&>(owner());
  const int n = robot.model_.nq;
  auto portOf = [&in](const char* field) {
    const std::uint64_t v = in.u64(field);
    if (v > static_cast<std::uint64_t>(CommandPort::MotorTorque)) in.fail(std::string("bad ") + field);
    return static_cast<CommandPort>(v);
  };
  // Everything the setters would refuse is refused here too: a state of bytes is no less checked than one of calls.
  auto finite = [&in](const Eigen::VectorXd& v, const char* what) {
    if (!v.allFinite()) in.fail(std::string(what) + ": a value that is not finite");
    return v;
  };
  in.tag("robot inputs");
  for (int k = 0; k < n; ++k) {
    for (CommandPort* p : {&port[static_cast<size_t>(k)], &applied_port[static_cast<size_t>(k)]}) {
      *p = portOf("command port");
      const std::string why = robot.portRefusal(k, *p);
      if (!why.empty()) in.fail(std::string("joint ") + std::to_string(k) + ": the " + portName(*p) + " port " + why);
    }
  }
  cmd = finite(in.vector("commands", n), "commands");
  applied_cmd = finite(in.vector("applied commands", n), "applied commands");
  ref_held = in.flags("held references", n);
  for (char h : ref_held)
    if (h != 0 && h != 1) in.fail("held references: expected 0 or 1");
  ref_q = finite(in.vector("held q", n), "held q");
  ref_qd = finite(in.vector("held qd", n), "held qd");
  ref_qdd = finite(in.vector("held qdd", n), "held qdd");
  q_start = finite(in.vector("start angles", n), "start angles");
  const std::uint64_t wrenches = in.u64("external wrenches");
  if (wrenches > robot.model_.frames.size()) in.fail("more external wrenches than frames");
  user_wrenches.clear();
  for (std::uint64_t i = 0; i < wrenches; ++i) {
    const std::int64_t f = in.i64("wrench frame");
    if (f < 0 || f >= static_cast<std::int64_t>(robot.model_.frames.size()) ||
        robot.model_.frames[static_cast<size_t>(f)].joint < 0)
      in.fail("wrench frame " + std::to_string(f) + ": not a frame on a moving body");
    for (const auto& w : user_wrenches)
      if (w.first == f) in.fail("two wrenches on frame " + std::to_string(f));
    const Eigen::VectorXd w = finite(in.vector("wrench", 6), "wrench");
    if (w.isZero(0.0)) in.fail("a zero wrench (setExternalWrench removes those)");
    user_wrenches.emplace_back(static_cast<int>(f), w);
  }
  in.tag("sampled control");
  ctrl_x = in.doubles("controller states", static_cast<long>(ctrl_x.size()));
  for (double x : ctrl_x)
    if (!std::isfinite(x)) in.fail("controller states: a value that is not finite");
  held_u = finite(in.vector("held outputs", n), "held outputs");
  held_i_ref = finite(in.vector("held current references", n), "held current references");
  held_q_fb = finite(in.vector("held joint feedback", n), "held joint feedback");
  prev_qm_meas = finite(in.vector("encoder memory", n), "encoder memory");
  first_sample = in.boolean("first sample");
  inner_count = in.i64("current-loop samples");
  if (inner_count < 0 || inner_count > (1L << 60)) in.fail("current-loop samples: out of range");
  std::mt19937_64 engine_read;
  std::normal_distribution<double> normal_read;
  if (!unstreamed(in.text("noise generator"), engine_read)) in.fail("bad noise generator state");
  if (!unstreamed(in.text("noise distribution"), normal_read) || normal_read.mean() != 0.0 ||
      normal_read.stddev() != 1.0)
    in.fail("bad noise distribution state (expected the standard normal distribution)");
  engine = engine_read;
  normal = normal_read;
  in.tag("faults");
  fault_applied = in.doubles("applied fault values", static_cast<long>(fault_applied.size()));
  for (size_t i = 0; i < fault_applied.size(); ++i)  // NaN: a parameter fault before its onset
    if (std::isinf(fault_applied[i]) || (std::isnan(fault_applied[i]) && !robot.faults_[i].parameterFault()))
      in.fail("applied fault values: a value that is not finite");
  if (in.u64("stuck episodes") != stuck_episode.size()) in.fail("another number of faults");
  for (long& e : stuck_episode) e = in.i64("stuck episode");
  stuck_value = in.doubles("stuck values", static_cast<long>(stuck_value.size()));
  for (double v : stuck_value)
    if (!std::isfinite(v)) in.fail("stuck values: a value that is not finite");
  in.tag("relative replay");
  anchor = finite(in.vector("replay anchors", n), "replay anchors");
  in.tag("load torques");
  loads.load(in);
  robot.rebuildDrives(*this, {});
}

}  // namespace jointsim::systems
