#pragma once
// Shared test helpers: matrix comparison with an explanatory failure message, seeded random states,
// paths to the source tree, a private temporary folder per test (TempDir) and the CLI run with its output
// captured in files no other call can share (runCli).
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <system_error>
#include <utility>
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

/// The folder temporary files go to: $TMPDIR, or /tmp when it is unset or empty.
inline std::filesystem::path tempRoot() {
  const char* t = std::getenv("TMPDIR");
  return std::filesystem::path(t != nullptr && *t != '\0' ? t : "/tmp");
}

/// `text` with every character other than [A-Za-z0-9._-] replaced by '_', at most `max_size` characters (a
/// file name part that needs no quoting).
inline std::string sanitizeFileName(const std::string& text, size_t max_size = 100) {
  std::string s = text.substr(0, max_size);
  for (char& c : s) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
    if (!ok) c = '_';
  }
  return s;
}

/// A new, empty folder `<tempRoot()>/<prefix>.XXXXXX` made by mkdtemp (the suffix random, so no other process
/// or call can get the same folder). Throws std::system_error when it cannot be made.
inline std::filesystem::path makeUniqueDir(const std::string& prefix) {
  std::string templ = (tempRoot() / (sanitizeFileName(prefix) + ".XXXXXX")).string();
  if (::mkdtemp(templ.data()) == nullptr) throw std::system_error(errno, std::generic_category(), "mkdtemp " + templ);
  return templ;
}

/// "Suite.Test" of the running GoogleTest test ("no_test" outside one).
inline std::string currentTestName() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return info == nullptr ? std::string("no_test") : std::string(info->test_suite_name()) + "." + info->name();
}

/// A private temporary folder of one test: made by mkdtemp under $TMPDIR (default /tmp), named after the running
/// test (suite.test, sanitized; `label` appended when given) and a random suffix, so that neither two tests
/// run in parallel nor two checkouts testing at once can share it. Removed with everything in it when it goes
/// out of scope, unless the running test has failed: then it is kept and its path printed to stderr, to look
/// at what the test left. Use it as a local in a TEST or as a member of a fixture (it is made when the
/// fixture is, and removed after TearDown).
class TempDir {
 public:
  explicit TempDir(const std::string& label = "")
      : path_(makeUniqueDir("jointsim_" + currentTestName() + (label.empty() ? "" : "_" + label))) {}
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  TempDir(TempDir&& other) noexcept : path_(std::exchange(other.path_, {})) {}
  TempDir& operator=(TempDir&&) = delete;
  ~TempDir() {
    if (path_.empty()) return;
    if (::testing::Test::HasFailure()) {
      std::cerr << "[ TempDir  ] kept for the failed test " << currentTestName() << ": " << path_.string() << "\n";
      return;
    }
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }

  const std::filesystem::path& path() const { return path_; }
  operator const std::filesystem::path&() const { return path_; }  // to pass it where a path is expected
  std::string string() const { return path_.string(); }
  std::filesystem::path operator/(const std::filesystem::path& relative) const { return path_ / relative; }

 private:
  std::filesystem::path path_;
};

/// `s` in single quotes for /bin/sh.
inline std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

/// Exit status (-1 when not a normal exit), stdout and stderr of one `jointsim` command.
struct CliResult {
  int status;
  std::string out, err;
};
/// Runs a shell command line (`command` must not redirect its own output). Its stdout and stderr are captured
/// in a folder of this call alone (makeUniqueDir), read back and removed, so no two calls, in one test or in
/// tests run in parallel, can mix their output.
inline CliResult runCommand(const std::string& command) {
  const std::filesystem::path dir = makeUniqueDir("jointsim_cmd_" + currentTestName());
  const std::filesystem::path out = dir / "stdout", err = dir / "stderr";
  const int rc = std::system((command + " >" + shellQuote(out.string()) + " 2>" + shellQuote(err.string())).c_str());
  CliResult result{WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, readText(out), readText(err)};
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  return result;
}

/// Runs the CLI with `args` (shell words), its output captured as by runCommand.
inline CliResult runCli(const std::string& args) { return runCommand(std::string(JOINTSIM_CLI_PATH) + " " + args); }

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
