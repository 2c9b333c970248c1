// The layers of the library, bottom up (src/CMakeLists.txt): a file of a layer may include headers of its own
// layer and of the layers below it, never of a layer above. This test reads every file of include/jointsim/
// and src/ and checks its #include "..." lines; it runs on a fixture with known violations to show it can fail.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

const std::vector<std::string> kLayers{"common",  "io",          "multibody", "drive",  "control", "sim",
                                       "systems", "experiments", "identify",  "report", "fmi"};

int rank(const std::string& layer) {
  const auto it = std::find(kLayers.begin(), kLayers.end(), layer);
  return it == kLayers.end() ? -1 : static_cast<int>(it - kLayers.begin());
}

/// The layer of an included path: "jointsim/<layer>/..." (public) or "<layer>/..." (internal, src/).
std::string includedLayer(const std::string& path) {
  std::string p = path;
  if (p.rfind("jointsim/", 0) == 0) p = p.substr(9);
  const size_t slash = p.find('/');
  return slash == std::string::npos ? std::string() : p.substr(0, slash);
}

struct Violation {
  std::string file;
  int line;
  std::string text;
};

/// Every include of a higher layer below `root` (its include/jointsim/<layer>/ and src/<layer>/ folders).
std::vector<Violation> violations(const fs::path& root) {
  std::vector<Violation> out;
  const std::regex include_re(R"re(^\s*#\s*include\s*"([^"]+)")re");
  for (const fs::path& base : {root / "include" / "jointsim", root / "src"}) {
    if (!fs::exists(base)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(base)) {
      if (!entry.is_regular_file()) continue;
      const fs::path rel = fs::relative(entry.path(), base);
      const std::string own = rel.begin()->string();
      const int own_rank = rank(own);
      if (own_rank < 0) continue;  // the umbrella header, CMakeLists.txt
      std::ifstream in(entry.path());
      std::string line;
      int n = 0;
      std::smatch m;
      while (std::getline(in, line)) {
        ++n;
        if (!std::regex_search(line, m, include_re)) continue;
        const int r = rank(includedLayer(m[1]));
        if (r > own_rank) out.push_back({entry.path().string(), n, m[1]});
      }
    }
  }
  return out;
}

}  // namespace

TEST(Layering, NoFileIncludesAHigherLayer) {
  const auto v = violations(jointsim::test::sourcePath(""));
  for (const auto& x : v) ADD_FAILURE() << x.file << ":" << x.line << ": includes " << x.text << " of a higher layer";
  EXPECT_TRUE(v.empty());
}

TEST(Layering, TheCheckFindsTheFixtureViolations) {
  const auto v = violations(jointsim::test::sourcePath("tests/data/layering_violation"));
  ASSERT_EQ(v.size(), 2u);
  std::vector<std::string> found;
  for (const auto& x : v)
    found.push_back(fs::path(x.file).filename().string() + ":" + std::to_string(x.line) + ":" + x.text);
  std::sort(found.begin(), found.end());
  EXPECT_EQ(found[0], "bad_motor.hpp:7:jointsim/experiments/registry.hpp");
  EXPECT_EQ(found[1], "bad_reader.cpp:4:report/gnuplot.hpp");
}

TEST(Layering, EveryLayerHasItsFolders) {
  // The list above matches the tree: a new layer must be added here and in src/CMakeLists.txt.
  for (const auto& layer : kLayers) {
    EXPECT_TRUE(fs::is_directory(jointsim::test::sourcePath("src/" + layer))) << layer;
    EXPECT_TRUE(fs::is_directory(jointsim::test::sourcePath("include/jointsim/" + layer))) << layer;
  }
  for (const auto& entry : fs::directory_iterator(jointsim::test::sourcePath("src"))) {
    if (entry.is_directory()) {
      EXPECT_GE(rank(entry.path().filename().string()), 0) << entry.path();
    }
  }
  // The same order as the build's layer list.
  std::ifstream cmake(jointsim::test::sourcePath("src/CMakeLists.txt"));
  std::string line, listed;
  while (std::getline(cmake, line))
    if (line.rfind("set(JOINTSIM_LAYERS ", 0) == 0 && line.find("${") == std::string::npos) listed = line;
  std::string expected = "set(JOINTSIM_LAYERS";
  for (const auto& layer : kLayers) expected += " " + layer;
  EXPECT_EQ(listed, expected + ")");
}
