// Accuracy at the stated tolerance: each MSL validation case, at the solver settings of its shipped file, against
// the same case at rtol 1e-10 / atol 1e-12 (an independent, far more accurate run of the same model).
#include <string>

#include <gtest/gtest.h>

#include "jointsim/experiments/experiment.hpp"
#include "test_util.hpp"

using namespace jointsim;

namespace {

/// The unit of a column name `name[unit]` ("" without one).
std::string unitOf(const std::string& column) {
  const auto open = column.rfind('[');
  return open == std::string::npos || column.back() != ']' ? "" : column.substr(open + 1, column.size() - open - 2);
}

sim::SignalTable run(const std::string& config, const std::vector<std::string>& overrides) {
  auto e = experiments::loadExperiment(test::sourcePath("config/experiments/" + config + ".yaml"), overrides);
  return experiments::runInMemory(*e).log;
}

/// Angles ([rad]) within 1e-4 rad, other signals within 1e-4 of their range in the tight run; a discrete mode
/// ([-], integer valued) may differ only at a row next to a switch of the tight run (event times move with the
/// tolerance by less than one output interval).
void expectAccurate(const std::string& config) {
  SCOPED_TRACE(config);
  const sim::SignalTable a = run(config, {}), ref = run(config, {"solver.rtol=1e-10", "solver.atol=1e-12"});
  ASSERT_EQ(a.columns, ref.columns);
  ASSERT_EQ(a.values.rows(), ref.values.rows());
  EXPECT_LE((a.values.col(0) - ref.values.col(0)).cwiseAbs().maxCoeff(), 1e-12) << "same output times";
  const Eigen::Index rows = ref.values.rows();
  for (size_t j = 1; j < ref.columns.size(); ++j) {
    const std::string& name = ref.columns[j];
    const Eigen::VectorXd x = a.values.col(static_cast<Eigen::Index>(j)),
                          r = ref.values.col(static_cast<Eigen::Index>(j));
    if (unitOf(name) == "-" && r.array().round().isApprox(r.array())) {
      for (Eigen::Index k = 0; k < rows; ++k) {
        if (x[k] == r[k]) continue;
        const bool near_switch = (k > 0 && r[k - 1] != r[k]) || (k + 1 < rows && r[k + 1] != r[k]);
        EXPECT_TRUE(near_switch) << name << " differs at t = " << ref.values(k, 0) << " s away from a switch";
      }
      continue;
    }
    const double bound = unitOf(name) == "rad" ? 1e-4 : 1e-4 * (r.maxCoeff() - r.minCoeff());
    EXPECT_LE((x - r).cwiseAbs().maxCoeff(), bound) << name;
  }
}

TEST(Accuracy, ValidationConfigsAgreeWithTheirTightRuns) {
  for (const char* config : {"msl_friction", "msl_backlash", "robotr3_one_axis", "robotr3_full_robot"})
    expectAccurate(config);
}

}  // namespace
