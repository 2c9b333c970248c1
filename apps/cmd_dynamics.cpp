// `jointsim dynamics`: rigid-body quantities of a robot at one state, as one JSON object on stdout.
#include <cstdlib>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/robot_loader.hpp"

namespace jointsim::cli {

Eigen::VectorXd parseList(const std::string& text, const std::string& option) {
  std::vector<double> values;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find(',', start), text.size());
    const std::string token = text.substr(start, end - start);
    char* stop = nullptr;
    const double v = std::strtod(token.c_str(), &stop);
    if (token.empty() || stop == token.c_str() || *stop != '\0' || !std::isfinite(v))
      throw InputError(option + ": expected comma-separated numbers, got '" + token + "' in '" + text + "'");
    values.push_back(v);
    start = end + 1;
  }
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

Eigen::VectorXd parseList(const std::string& text, const std::string& option, Eigen::Index expected,
                          const std::string& what) {
  Eigen::VectorXd v = parseList(text, option);
  if (v.size() != expected)
    throw InputError(option + ": expected " + std::to_string(expected) + " comma-separated values (" + what +
                     "), got " + std::to_string(v.size()));
  return v;
}

namespace {
struct DynamicsOptions {
  std::string robot, q, qd, qdd, tau, frame, gravity;
};
}  // namespace

void addDynamicsCommand(CLI::App& app) {
  auto opt = std::make_shared<DynamicsOptions>();
  CLI::App* cmd = app.add_subcommand(
      "dynamics", "Print RNEA torques, M(q), g(q), forward dynamics (with --tau) and a frame pose as one JSON object");
  cmd->add_option("--robot", opt->robot, "Robot description (.urdf, .yaml)")->required();
  cmd->add_option("--q", opt->q, "Joint positions q1,...,qn [rad or m], base to tip")->required();
  cmd->add_option("--qd", opt->qd, "Joint velocities [rad/s or m/s] (default zeros)");
  cmd->add_option("--qdd", opt->qdd, "Joint accelerations [rad/s² or m/s²] (default zeros)");
  cmd->add_option("--tau", opt->tau, "Joint torques [N·m or N]: adds \"qdd\" = forward dynamics");
  cmd->add_option("--frame", opt->frame, "Frame for \"tcp\" (default: the last link of the chain)");
  cmd->add_option("--gravity", opt->gravity, "Override gravity gx,gy,gz [m/s²] in the base frame");
  cmd->callback([opt] {
    using namespace jointsim::multibody;
    Model model = loadRobot(opt->robot);
    const Eigen::Index n = model.nq;
    const std::string per_joint = "one per joint of robot '" + model.name + "', which has " + std::to_string(n);
    if (!opt->gravity.empty()) model.gravity = parseList(opt->gravity, "--gravity", 3, "gx,gy,gz in m/s²");
    const Eigen::VectorXd q = parseList(opt->q, "--q", n, per_joint);
    const Eigen::VectorXd qd = opt->qd.empty() ? Eigen::VectorXd::Zero(n) : parseList(opt->qd, "--qd", n, per_joint);
    const Eigen::VectorXd qdd =
        opt->qdd.empty() ? Eigen::VectorXd::Zero(n) : parseList(opt->qdd, "--qdd", n, per_joint);
    const int frame = model.frameIndex(opt->frame.empty() ? model.tip_frame : opt->frame);
    Data data(model);

    // Numbers as the shortest text that reads back to the same double.
    auto vec = [](const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
    auto rows = [&vec](const Eigen::MatrixXd& m) {
      nlohmann::ordered_json out = nlohmann::ordered_json::array();
      for (Eigen::Index r = 0; r < m.rows(); ++r) out.push_back(vec(m.row(r).transpose()));
      return out;
    };
    nlohmann::ordered_json out;
    out["tau"] = vec(rnea(model, data, q, qd, qdd));
    out["M"] = rows(crba(model, data, q));
    out["g"] = vec(gravityTorques(model, data, q));
    if (!opt->tau.empty()) {
      const Eigen::VectorXd tau = parseList(opt->tau, "--tau", n, per_joint);
      out["qdd"] = vec(aba(model, data, q, qd, tau));
    }
    forwardKinematics(model, data, q);
    out["tcp"] = rows(data.oMf[static_cast<size_t>(frame)].homogeneous());
    std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
  });
}

}  // namespace jointsim::cli
