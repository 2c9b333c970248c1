#pragma once
// Shared test helpers: matrix comparison with an explanatory failure message, seeded random states,
// and paths to the source tree.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "jointsim/sim/plant.hpp"
#include "jointsim/sim/simulate.hpp"

namespace jointsim::test {

inline std::string sourcePath(const std::string& relative) { return std::string(JOINTSIM_SOURCE_DIR) + "/" + relative; }

/// The whole content of a file ("" when it cannot be read).
inline std::string readText(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Exit status (-1 when not a normal exit), stdout and stderr of one `jointsim` command.
struct CliResult {
  int status;
  std::string out, err;
};
/// Runs the CLI with `args` (shell words), its output captured in `<tag>.out` / `<tag>.err` in the temp folder.
inline CliResult runCli(const std::string& args, const std::string& tag) {
  const auto base = std::filesystem::temp_directory_path() / tag;
  const std::string out = base.string() + ".out", err = base.string() + ".err";
  const int rc = std::system((std::string(JOINTSIM_CLI_PATH) + " " + args + " >" + out + " 2>" + err).c_str());
  return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, readText(out), readText(err)};
}

/// Index in a simulate() row (time first) of the plant's signal `name` ("time": 0).
inline int rowIndex(const sim::Plant& plant, const std::string& name) {
  return name == "time" ? 0 : 1 + sim::signalIndex(plant, name);
}

/// Runs a plant with options (defaults: its own) and returns every row.
template <class P>
std::vector<Eigen::VectorXd> simulateRows(P& plant) {
  std::vector<Eigen::VectorXd> rows;
  sim::simulate(plant, plant.simulateOptions(), [&](const Eigen::VectorXd& r) { rows.push_back(r); });
  return rows;
}

/// |a − b| ≤ tol·max(1, |b|) entrywise; on failure names the worst entry, both values and the difference.
inline ::testing::AssertionResult MatricesNear(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double tol) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return ::testing::AssertionFailure() << "size mismatch: " << a.rows() << "x" << a.cols() << " vs " << b.rows()
                                         << "x" << b.cols();
  }
  double worst = -1.0;
  Eigen::Index wr = 0, wc = 0;
  for (Eigen::Index r = 0; r < a.rows(); ++r)
    for (Eigen::Index c = 0; c < a.cols(); ++c) {
      const double err = std::abs(a(r, c) - b(r, c)) / std::max(1.0, std::abs(b(r, c)));
      if (!(err <= worst)) {
        worst = err;
        wr = r;
        wc = c;
      }
    }
  if (worst <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "entry (" << wr << "," << wc << "): " << a(wr, wc) << " vs " << b(wr, wc)
                                       << ", scaled difference " << worst << " > tolerance " << tol;
}

/// Deterministic random vector with entries uniform in [lo, hi].
inline Eigen::VectorXd randomVector(std::mt19937& rng, Eigen::Index n, double lo, double hi) {
  std::uniform_real_distribution<double> dist(lo, hi);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = dist(rng);
  return v;
}

}  // namespace jointsim::test
