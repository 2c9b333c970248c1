// Names of earlier versions in files: refused with a message that names the new name (and where the old one is).
#include <fstream>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jointsim/common/error.hpp"
#include "jointsim/systems/robot_with_drives.hpp"
#include "test_util.hpp"

namespace jointsim {
namespace {

using ::testing::HasSubstr;

TEST(RenamedKeys, OldControllerTypesNameTheirNewNames) {
  std::ifstream in(test::sourcePath("config/robots/ur5_drives.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  const std::string original = text.str();
  const test::TempDir dir;
  std::ofstream(dir.path() / "ur5.yaml") << std::ifstream(test::sourcePath("config/robots/ur5.yaml")).rdbuf();
  for (const auto& [old_name, new_name] :
       {std::pair<std::string, std::string>{"cascade_002", "voltage_cascade"}, {"motor_ppi_000", "torque_cascade"}}) {
    std::string drives = original;
    const size_t at = drives.find("type: voltage_cascade");
    ASSERT_NE(at, std::string::npos);
    drives.replace(at, 21, "type: " + old_name);
    const std::string path = (dir.path() / ("drives_" + old_name + ".yaml")).string();
    std::ofstream(path) << drives;
    try {
      systems::loadRobotWithDrives(path);
      FAIL() << old_name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("'" + old_name + "' was renamed: use '" + new_name + "'"));
      EXPECT_EQ(e.file(), path);
      EXPECT_GT(e.line(), 0);
    }
  }
}

}  // namespace
}  // namespace jointsim
