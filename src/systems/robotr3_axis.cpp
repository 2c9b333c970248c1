// The RobotR3 axis on a load ([MSL, RobotR3.OneAxis]) as a configuration of the RobotR3 robot (robotr3_axis.hpp).
#include "jointsim/systems/robotr3_axis.hpp"

#include <cmath>
#include <string>

#include "jointsim/common/check.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/multibody/model.hpp"

namespace jointsim::systems {

void RobotR3AxisSetup::validate() const {
  // Keys as in a robotr3_axis experiment file.
  const char* const a = "RobotR3 axis";
  try {
    axis.motor.validate();
  } catch (const InputError& e) {
    throw InputError::parameter(a, "motor." + e.keyPath(), e.message());
  }
  check::that(axis.type == 1, a, "gear.type", "expected 1 (the rigid type 2 is not modelled on a 1-D load)");
  check::nonZero(a, "gear.ratio", axis.ratio, "(-)");
  check::positive(a, "gear.c", axis.c, "N·m/rad");
  check::nonNegative(a, "gear.d", axis.d, "N·m·s/rad");
  check::nonNegative(a, "gear.Rv0", axis.Rv0, "N·m");
  check::nonNegative(a, "gear.Rv1", axis.Rv1, "N·m·s/rad");
  check::atLeast(a, "gear.peak", axis.peak, 1.0, "(-)");
  check::nonNegative(a, "controller.kp", axis.kp, "1/s");
  check::nonNegative(a, "controller.ks", axis.ks, "A·s/rad");
  check::positive(a, "controller.Ts", axis.Ts, "s");
  check::positive(a, "load.inertia", load_inertia, "kg·m²");
  check::positive(a, "stop_time", stop_time, "s");
  check::positive(a, "log_interval", log_interval, "s");
  check::that(std::abs(sa0) <= axis.peak * axis.Rv0, a, "initial_friction_torque",
              "expected a torque within ±peak·Rv0 = ±" + formatNumber(axis.peak * axis.Rv0) + " N·m, got " +
                  formatNumber(sa0));
}

RobotR3FullSetup oneAxisRobot(const RobotR3AxisSetup& setup) {
  setup.validate();
  RobotR3FullSetup r;
  r.name = setup.name;
  // The joint, named by the prefix (which names its ports). Its dynamics are the fixed load inertia below; the
  // model's body (massless, J_load about the vertical axis) describes the same load for the multibody layer.
  multibody::ModelBuilder b(setup.name, "base");
  multibody::JointSpec j;
  j.name = setup.prefix;
  j.axis = Eigen::Vector3d::UnitZ();
  multibody::BodyInertia load;
  load.mass = 0.0;
  load.inertia = setup.load_inertia * Eigen::Matrix3d::Identity();
  b.addLink("base", j, "load", load);
  r.arm = b.build();
  r.axes = {setup.axis};
  auto one = [](double v) { return Eigen::VectorXd::Constant(1, v); };
  r.q_begin = one(setup.q_begin);
  r.q_end = one(setup.q_end);
  r.qd_max = one(setup.qd_max);
  r.qdd_max = one(setup.qdd_max);
  r.start_time = setup.start_time;
  r.swing_time = setup.swing_time;
  r.stop_time = setup.stop_time;
  r.log_interval = setup.log_interval;
  r.solver = setup.solver;
  r.initial_friction = one(setup.sa0);
  r.load_inertia = one(setup.load_inertia);  // the 1-D load: M̄ = J_load, no multibody recursion in the right-hand side
  r.energy = true;
  r.one_axis_prefix = setup.prefix;
  return r;
}

}  // namespace jointsim::systems
