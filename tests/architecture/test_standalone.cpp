// The repository stands on its own: the product (headers, sources, CLI, configs, docs, README) cites its
// sources by key ([Raviola2023, eq. 7], full citations in docs/references.md) and never points at documents a
// user does not have (internal source numbering such as "seed 002" or "(000 §3.9)", the internal model
// reference, the RobotR3 description, ../shared). A fixture line shows that the check can fail.
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

const std::regex& forbidden() {
  static const std::regex re(
      R"re(seeds? ?[0-9]|seed-0|MODEL_REFERENCE|ROBOTR3\.md|\.\./shared|\b00[0-4]('s| ?§| A\.[0-9]| eqs?\.| Table| Fig| Algorithm| Listing| Appendix)|\(00[0-4][ ,)])re",
      std::regex::icase);
  return re;
}

/// "file:line: text" of every forbidden reference in `text`.
std::vector<std::string> findings(const std::string& name, std::istream& in) {
  std::vector<std::string> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (std::regex_search(line, forbidden())) out.push_back(name + ":" + std::to_string(n) + ": " + line);
  }
  return out;
}

}  // namespace

TEST(StandsOnItsOwn, ProductCitesSourcesByKeyOnly) {
  const fs::path root = jointsim::test::sourcePath("");
  std::vector<std::string> all;
  size_t files = 0;
  for (const char* dir : {"include", "src", "apps", "config", "docs"}) {
    for (const auto& e : fs::recursive_directory_iterator(root / dir)) {
      if (!e.is_regular_file()) continue;
      std::ifstream in(e.path());
      const auto f = findings(fs::relative(e.path(), root).string(), in);
      all.insert(all.end(), f.begin(), f.end());
      ++files;
    }
  }
  std::ifstream readme(root / "README.md");
  const auto f = findings("README.md", readme);
  all.insert(all.end(), f.begin(), f.end());
  EXPECT_GT(files, 100u) << "the tree was read";
  for (const auto& x : all) ADD_FAILURE() << x;
  EXPECT_TRUE(all.empty());
  EXPECT_TRUE(fs::is_regular_file(root / "docs" / "references.md"));
  EXPECT_TRUE(fs::is_regular_file(root / "LICENSE"));
}

TEST(StandsOnItsOwn, TheCheckFindsInternalReferences) {
  std::istringstream text("// Friction of seed 002 (fine: [Raviola2023, eq. 7])\n"
                          "x = 1;  // see MODEL_REFERENCE §3.7\n"
                          "// clamp (000 §3.9, A.11) and 001's Algorithm II, ../shared/ROBOTR3.md\n"
                          "control: {rate: 2000, seed: 7}   # a random seed is fine\n"
                          "// [Olsson2017, A.12] is fine, 9000 N/m is fine\n");
  const auto f = findings("fixture", text);
  ASSERT_EQ(f.size(), 3u);
  EXPECT_EQ(f[0].rfind("fixture:1:", 0), 0u);
  EXPECT_EQ(f[1].rfind("fixture:2:", 0), 0u);
  EXPECT_EQ(f[2].rfind("fixture:3:", 0), 0u);
}

TEST(StandsOnItsOwn, UmbrellaHeaderIncludesEveryPublicHeader) {
  std::ifstream in(jointsim::test::sourcePath("include/jointsim/jointsim.hpp"));
  std::stringstream umbrella;
  umbrella << in.rdbuf();
  const fs::path root = jointsim::test::sourcePath("include");
  int headers = 0;
  for (const auto& entry : fs::recursive_directory_iterator(root / "jointsim")) {
    if (entry.path().extension() != ".hpp" || entry.path().filename() == "jointsim.hpp") continue;
    ++headers;
    const std::string rel = fs::relative(entry.path(), root).generic_string();
    EXPECT_NE(umbrella.str().find("#include \"" + rel + "\""), std::string::npos) << rel << " is not in jointsim.hpp";
  }
  EXPECT_GT(headers, 50);
}
