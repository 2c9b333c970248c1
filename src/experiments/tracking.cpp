#include "jointsim/experiments/tracking.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>

#include <Eigen/Geometry>

#include "control/trajectory_yaml.hpp"
#include "experiments/config_common.hpp"
#include "experiments/joint_rig_yaml.hpp"
#include "experiments/tracking_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/sim/hybrid_run.hpp"
#include "jointsim/control/trajectory.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"

namespace jointsim::experiments {

using io::YamlValue;

namespace {

control::JointControllerParams readController(const YamlValue& node) {
  control::JointControllerParams p;
  if (!node.defined()) return p;
  node.expectMap("a controller mapping {type, gains...}");
  const YamlValue type = node.required("type", "cascade_002, motor_ppi_000 or none");
  const std::string t = type.asString("a controller type");
  auto gain = [&](const char* key, const std::string& unit) {
    const YamlValue g = node.required(key, std::string("gain in ") + unit);
    const double v = g.asDouble("a gain in " + unit);
    if (!(v >= 0.0)) g.failExpected("a gain >= 0 " + unit + " (negative gains destabilise the loop)");
    return v;
  };
  if (t == "cascade_002") {
    node.allowKeys({"type", "P_pos", "P_vel", "I_vel", "P_cur", "I_cur"});
    p.type = control::ControllerType::Cascade002;
    p.P_pos = gain("P_pos", "1/s");
    p.P_vel = gain("P_vel", "A·s/rad");
    p.I_vel = gain("I_vel", "A/rad");
    p.P_cur = gain("P_cur", "V/A");
    p.I_cur = gain("I_cur", "V/(A·s)");
  } else if (t == "motor_ppi_000") {
    node.allowKeys({"type", "kp", "ks", "Ts"});
    p.type = control::ControllerType::MotorPPI000;
    p.kp = gain("kp", "1/s");
    p.ks = gain("ks", "N·m·s/rad");
    const YamlValue ts = node.required("Ts", "PI time constant in s");
    p.Ts = ts.asDouble("a time constant in s");
    if (!(p.Ts > 0)) ts.failExpected("a time constant > 0 s");
  } else if (t == "none") {
    node.allowKeys({"type"});
  } else {
    type.failExpected("cascade_002, motor_ppi_000 or none");
  }
  return p;
}

}  // namespace

sim::RobotSystem loadRobotWithDrives(const std::string& path, const std::vector<sim::Fault>& faults) {
  const YamlValue root = YamlValue::loadFile(path);
  root.expectMap("a robot-with-drives mapping {name, multibody, drives, coupling}");
  root.allowKeys({"name", "multibody", "drives", "coupling"});
  const YamlValue mb = root.required("multibody", "multibody description file, relative to this file");
  multibody::Model model;
  try {
    model = multibody::loadRobot(mb.asPath());
  } catch (const InputError& e) {
    mb.fail(std::string("cannot load the multibody description: ") + e.what());
  }
  if (root.has("name")) model.name = root["name"].asString("a robot name");
  const YamlValue drives = root.required("drives", "one drive per joint");
  drives.expectSequence("a list of drives");
  std::vector<sim::DriveSpec> specs;
  std::vector<std::string> named;
  for (size_t k = 0; k < drives.size(); ++k) {
    const YamlValue d = drives.at(k);
    d.expectMap("a drive mapping {joint, motor, electrics, transmission, friction, controller}");
    d.allowKeys({"joint", "motor", "electrics", "transmission", "friction", "controller", "sensors"});
    sim::DriveSpec s;
    const YamlValue joint = d.required("joint", "name of the joint this drive moves");
    s.joint = joint.asString("a joint name");
    try {
      model.jointIndex(s.joint);
    } catch (const InputError& e) {
      joint.fail(e.what());
    }
    for (const auto& n : named)
      if (n == s.joint) joint.fail("joint '" + s.joint + "' has two drives");
    named.push_back(s.joint);
    s.motor = detail::readMotor(d.required("motor", "motor parameters"));
    s.transmission = detail::readTransmission(d.required("transmission", "the transmission"));
    if (d.has("friction")) s.friction = detail::readFrictionModel(d["friction"]);
    s.controller = readController(d["controller"]);
    if (const YamlValue sn = d["sensors"]; sn.defined()) {
      sn.expectMap("a sensors mapping {joint_quantum, motor_quantum, current_quantum, joint_noise, motor_velocity_noise, current_noise}");
      sn.allowKeys({"joint_quantum", "motor_quantum", "current_quantum", "joint_noise", "motor_velocity_noise", "current_noise",
                    "joint_bias"});
      s.sensors.joint_bias = sn["joint_bias"].asDouble(0.0, "a joint-angle bias in rad");
      auto nonneg = [&](const char* key, const char* unit) {
        const double v = sn[key].asDouble(0.0, std::string("a value in ") + unit);
        if (v < 0.0) sn[key].failExpected(std::string("a value >= 0 ") + unit);
        return v;
      };
      s.sensors.joint_quantum = nonneg("joint_quantum", "rad");
      s.sensors.motor_quantum = nonneg("motor_quantum", "rad");
      s.sensors.current_quantum = nonneg("current_quantum", "A");
      s.sensors.joint_noise = nonneg("joint_noise", "rad");
      s.sensors.motor_velocity_noise = nonneg("motor_velocity_noise", "rad/s");
      s.sensors.current_noise = nonneg("current_noise", "A");
    }
    s.electrics = d.has("electrics") ? d["electrics"].asBool("true or false")
                                     : s.controller.type == control::ControllerType::Cascade002;
    specs.push_back(std::move(s));
  }
  for (const auto& jn : model.joint_names) {
    bool found = false;
    for (const auto& n : named) found = found || n == jn;
    if (!found) drives.fail("joint '" + jn + "' has no drive (expected one drive per joint of " + model.name + ")");
  }
  Eigen::MatrixXd G;
  if (const YamlValue c = root["coupling"]; c.defined()) {
    c.expectSequence("an n×n matrix as a list of rows");
    const auto n = static_cast<size_t>(model.nq);
    if (c.size() != n) c.failExpected(std::to_string(n) + " rows");
    G.resize(model.nq, model.nq);
    for (size_t r = 0; r < n; ++r) {
      const auto row = c.at(r).asDoubles(n, "a row of " + std::to_string(n) + " numbers");
      for (size_t col = 0; col < n; ++col) G(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(col)) = row[col];
    }
  }
  sim::applyFaults(specs, faults);  // InputError names the fault
  try {
    return sim::RobotSystem(std::move(model), std::move(specs), G);
  } catch (const InputError& e) {
    root.fail(e.what());
  }
}

namespace detail {

RunReport runTracking(const YamlValue& root, const std::string& config_path, const std::string& name,
                      const RunOptions& options) {
  root.allowKeys({"experiment", "robot", "trajectory", "initial_state", "duration", "log_rate", "solver", "check_limits",
                  "control"});
  const std::string base_dir = std::filesystem::path(config_path).parent_path().string();
  const YamlValue robot = root.required("robot", "robot-with-drives file, relative to this file");
  const std::string robot_path = robot.asPath();
  sim::RobotSystem sys = [&] {
    try {
      return loadRobotWithDrives(robot_path, options.faults);
    } catch (const InputError& e) {
      robot.fail(std::string("cannot load robot: ") + e.what());
    }
  }();
  const int n = sys.dof();
  double control_rate = 0.0;
  if (const YamlValue c = root["control"]; c.defined()) {
    c.expectMap("a mapping {rate: Hz, seed}");
    c.allowKeys({"rate", "seed"});
    const YamlValue rate = c.required("rate", "control sampling rate in Hz");
    control_rate = rate.asDouble("a rate in Hz");
    if (!(control_rate > 0.0)) rate.failExpected("a rate > 0 Hz");
    const long seed = c["seed"].defined() ? c["seed"].asInt("an integer seed") : 1;
    sys.setSampledControl(control_rate, static_cast<unsigned>(seed));
  }
  const std::shared_ptr<const control::JointTrajectory> traj =
      control::trajectoryFromYaml(root.required("trajectory", "the reference trajectory"), n, base_dir);
  const bool check = !root.has("check_limits") || root["check_limits"].asBool("true or false");
  if (check) {
    try {
      control::checkLimits(*traj, sys.model().joint_names, sys.model().limits);
    } catch (const InputError& e) {
      root["trajectory"].fail(e.what());
    }
  }
  const YamlValue duration_node = root["duration"];
  const double duration = duration_node.asDouble(traj->duration(), "a time in s");
  if (!(duration > 0)) duration_node.failExpected("a time > 0 s");
  const double log_rate = root["log_rate"].asDouble(500.0, "a rate in Hz");
  if (!(log_rate > 0)) root["log_rate"].failExpected("a rate > 0 Hz");
  sim::CvodeOptions solver;
  solver.method = sim::Method::BDF;
  solver.max_order = 2;  // A-stable: lightly damped kHz gear modes (docs/design.md)
  solver.rtol = 1e-6;
  solver.atol = 1e-9;
  solver = readSolver(root["solver"], solver);
  if (solver.max_step == 0.0) solver.max_step = 1.0 / log_rate;
  if (solver.component.empty()) solver.component = "UR5 twin '" + sys.model().name + "'";

  sys.setSetpoints([traj](double t, Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> qd, Eigen::Ref<Eigen::VectorXd> qdd) {
    traj->evaluate(t, q, qd, qdd);
  });
  Eigen::VectorXd q0(n), tmp1(n), tmp2(n);
  traj->evaluate(0.0, q0, tmp1, tmp2);
  if (const YamlValue init = root["initial_state"]; init.defined()) {
    init.expectMap("a mapping {q}");
    init.allowKeys({"q"});
    const auto v = init["q"].asDoubles(static_cast<size_t>(n), std::to_string(n) + " joint positions in rad");
    q0 = Eigen::Map<const Eigen::VectorXd>(v.data(), n);
  }
  TrackingLogger logger(sys);
  Eigen::VectorXd max_err = Eigen::VectorXd::Zero(n);
  const RunReport report = runAndRecord(
      name, "tracking", options, logger.columns(),
      [&](const std::function<void(const Eigen::VectorXd&)>& sink) {
        Eigen::VectorXd y = sys.initialState(q0);
        auto emit = [&](double t, const Eigen::Ref<const Eigen::VectorXd>& yy) {
          const Eigen::VectorXd& row = logger.row(t, yy);
          max_err = max_err.cwiseMax((sys.signals(t, yy).q_set - yy.head(n)).cwiseAbs());
          sink(row);
        };
        const auto steps = static_cast<long>(std::ceil(duration * log_rate - 1e-9));
        if (!sys.sampled()) {
          // Continuous control: restart only at the trajectory's acceleration jumps.
          sim::HybridSystem hs;
          hs.n_states = sys.stateSize();
          hs.rhs = [&sys](double t, const Eigen::Ref<const Eigen::VectorXd>& yy, Eigen::Ref<Eigen::VectorXd> yd) {
            sys.derivatives(t, yy, yd);
          };
          hs.on_event = [](double, const Eigen::Ref<const Eigen::VectorXd>&, const std::vector<int>&) {};
          hs.output = emit;
          sim::HybridRunSettings run;
          run.t_end = duration;
          run.time_events = traj->breakpoints();
          run.n_outputs = steps;
          run.output_time = [&](long k) { return std::min(duration, static_cast<double>(k) / log_rate); };
          const sim::HybridRunResult r = sim::runHybrid(hs, solver, y, run);
          return SimulationOutcome{r.stats, r.sim_time_s, r.wall_time_s};
        }
        sim::CvodeIntegrator integ(sys.stateSize(), [&sys](double t, const Eigen::Ref<const Eigen::VectorXd>& yy, Eigen::Ref<Eigen::VectorXd> yd) {
          sys.derivatives(t, yy, yd);
        }, solver);
        const auto start = std::chrono::steady_clock::now();
        sys.controlStep(0.0, y);  // the held outputs at t = 0
        integ.initialize(0.0, y);
        emit(0.0, y);
        double t_reached = 0.0;
        {
          // Zero-order hold: one controller update per sample, CVODE restarted after each (held inputs
          // jump), never stepping across a sample; logs interleaved at their own times.
          const double Ts = 1.0 / control_rate;
          long next_log = 1;
          const auto samples = static_cast<long>(std::ceil(duration * control_rate - 1e-9));
          for (long s_k = 0; s_k < samples; ++s_k) {
            const double t_k = s_k * Ts, t_next = std::min(duration, (s_k + 1) * Ts);
            if (s_k > 0) {  // the update at t = 0 was made before the first log row
              sys.controlStep(t_k, y);
              integ.initialize(t_k, y);
            }
            integ.setStopTime(t_next);
            while (next_log <= steps && std::min(duration, next_log / log_rate) <= t_next + 1e-12) {
              const double t_log = std::min(duration, next_log / log_rate);
              t_reached = integ.advance(std::min(t_log, t_next), y);
              emit(t_reached, y);
              ++next_log;
            }
            if (t_reached < t_next) t_reached = integ.advance(t_next, y);
          }
          SimulationOutcome out;
          out.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          out.sim_time_s = t_reached;
          out.stats = integ.stats();
          return out;
        }
      },
      [&](io::JsonWriter& w) {
        w.beginObject();
        w.key("config_file"); w.value(config_path);
        w.key("robot_file"); w.value(robot_path);
        w.key("robot"); w.value(sys.model().name);
        w.key("joints"); w.beginArray(); for (const auto& j : sys.model().joint_names) w.value(j); w.endArray();
        w.key("trajectory"); w.value(traj->describe());
        w.key("state_size"); w.value(sys.stateSize());
        w.key("drives");
        w.beginArray();
        for (const auto& d : sys.drives()) {
          w.beginObject();
          w.key("joint"); w.value(d.joint);
          w.key("transmission"); w.value(d.transmission->type());
          w.key("ratio"); w.value(d.transmission->ratio());
          w.key("friction"); w.value(d.friction ? d.friction->type() : std::string("none"));
          w.key("electrics"); w.value(d.electrics);
          w.endObject();
        }
        w.endArray();
        w.key("max_tracking_error_rad"); w.value(max_err);
        w.key("control_rate_hz"); w.value(control_rate);
        w.key("duration"); w.value(duration);
        w.key("log_rate"); w.value(log_rate);
        w.key("solver"); writeSolverOptions(w, solver);
        w.key("config"); writeYamlAsJson(w, root.node());
        w.endObject();
      },
      duration);
  return report;
}

}  // namespace detail
}  // namespace jointsim::experiments
