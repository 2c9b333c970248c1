// Downstream use of the installed library: load a robot, check RNEA against M q̈ + nle.
#include <iostream>

#include <jointsim/jointsim.hpp>

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const auto model = jointsim::multibody::loadRobot(argv[1]);
  jointsim::multibody::Data data(model);
  Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(model.nq, 0.1, 0.6), qd = q, qdd = -q;
  const Eigen::VectorXd tau = jointsim::multibody::rnea(model, data, q, qd, qdd);
  const Eigen::MatrixXd M = jointsim::multibody::crba(model, data, q);
  const Eigen::VectorXd nle = jointsim::multibody::nonLinearEffects(model, data, q, qd);
  const double err = (M * qdd + nle - tau).norm();
  std::cout << "consumer: robot " << model.name << ", nq " << model.nq << ", |M qdd + nle - tau| = " << err << '\n';
  return err < 1e-9 ? 0 : 1;
}
