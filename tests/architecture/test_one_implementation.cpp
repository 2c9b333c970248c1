// One implementation of the hybrid mode iteration and of each controller law (issue: one composable model): every
// model with exact stick–slip friction runs the event iteration drive::iterateFrictionModes (msl_friction.hpp), and
// the control laws — the TorqueCascade / RobotR3 axis controller, the VoltageCascade, the rig's velocity PI — are
// written once, in src/control/joint_controller.cpp; the input methods of the models with held input ports once, in
// sim::HeldInputPlant. The check reads every file of include/jointsim/ and src/ for the
// marks of a law written out (a PI integrator ẋ = u/Ts, an integral gain times an integral, a friction mode step
// outside its one iteration, a hand-written iteration loop); it runs on a fixture with a copy of each to show it can fail.
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

struct Rule {
  const char* what;
  std::regex pattern;
  std::vector<std::string> allowed;  // files (relative to the root) that may contain it: the one implementation
};

const std::vector<Rule>& rules() {
  static const std::vector<Rule> r{
      {"a friction mode step (nextFrictionMode) outside the one event iteration",
       std::regex(R"(nextFrictionMode\s*\()"),
       {"include/jointsim/drive/msl_friction.hpp", "src/drive/msl_friction.cpp"}},
      {"a hand-written event iteration loop (for (int iter ...))", std::regex(R"(for\s*\(\s*int\s+iter\b)"), {}},
      {"a PI integrator written out (a state derivative divided by a Ts)",
       std::regex(R"(dot\s*\[[^\]]*\]\s*=[^;]*/\s*[A-Za-z_.>-]*\bTs\b)"),
       {"src/control/joint_controller.cpp"}},
      {"an integral gain applied (I_vel, I_cur, ki times a state)",
       std::regex(R"(\b(I_vel|I_cur|ki)\s*\*)"),
       {"src/control/joint_controller.cpp"}},
      {"a proportional gain applied to a velocity or current error (P_vel, P_cur)",
       std::regex(R"(\b(P_vel|P_cur)\s*\*)"),
       {"src/control/joint_controller.cpp"}},
      {"a held input port set or released outside sim::HeldInputPlant (the one implementation of the input methods)",
       std::regex(R"(\binputs\.(set|release)\s*\()"),
       {"src/sim/held_inputs.cpp"}},
  };
  return r;
}

std::vector<std::string> findings(const fs::path& root) {
  std::vector<std::string> out;
  for (const fs::path& base : {root / "include" / "jointsim", root / "src"}) {
    if (!fs::exists(base)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(base)) {
      if (!entry.is_regular_file()) continue;
      const std::string rel = fs::relative(entry.path(), root).generic_string();
      std::ifstream in(entry.path());
      std::string line;
      int n = 0;
      while (std::getline(in, line)) {
        ++n;
        const auto comment = line.find("//");
        const std::string code = comment == std::string::npos ? line : line.substr(0, comment);
        for (const Rule& r : rules()) {
          if (!std::regex_search(code, r.pattern)) continue;
          bool ok = false;
          for (const auto& a : r.allowed) ok = ok || rel == a;
          if (!ok) out.push_back(rel + ":" + std::to_string(n) + ": " + r.what + ": " + line);
        }
      }
    }
  }
  return out;
}

std::string joined(const std::vector<std::string>& v) {
  std::ostringstream s;
  for (const auto& x : v) s << x << "\n";
  return s.str();
}

}  // namespace

TEST(OneImplementation, ModeIterationAndControllerLawsAreWrittenOnce) {
  const auto f = findings(jointsim::test::sourcePath(""));
  EXPECT_TRUE(f.empty()) << joined(f);
}

TEST(OneImplementation, EveryStickSlipModelUsesTheOneEventIteration) {
  // The models with exact stick–slip friction (root functions drive::frictionRoots) call the one iteration.
  const fs::path systems = fs::path(jointsim::test::sourcePath("src/systems"));
  int models = 0;
  for (const auto& entry : fs::directory_iterator(systems)) {
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    if (text.str().find("frictionRoots(") == std::string::npos) continue;
    ++models;
    EXPECT_NE(text.str().find("iterateFrictionModes("), std::string::npos) << entry.path();
  }
  EXPECT_GE(models, 3);  // drive chain, RobotR3 robot (also the one-axis configuration), clamped robot
}

TEST(OneImplementation, TheCheckFindsCopies) {
  const jointsim::test::TempDir dir;
  fs::create_directories(dir / "src" / "systems");
  std::ofstream(dir / "src" / "systems" / "copy.cpp")
      << "  for (int iter = 0; iter < 30; ++iter) {\n"
         "    const FrictionMode m = drive::nextFrictionMode(st.modes[k], false, S, w, a, t0, t0max, f);\n"
         "  ydot[c] = st.e[j] / a.Ts;\n"
         "  const double raw = s_.pi.kp * err + s_.pi.ki * y[e_idx_];\n"
         "  out.i_ref = P_vel * e_vel;  // ydot = e / Ts in a comment is fine\n"
         "  if (st.inputs.set(static_cast<size_t>(port), value, ports_, name())) st.inputsChanged();\n";
  const auto f = findings(dir.path());
  EXPECT_EQ(f.size(), 6u) << joined(f);
}
