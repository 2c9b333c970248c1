#include "jointsim/common/version.hpp"

#include <ctime>

// The version comes from CMake's project() through the generated header; the commit from a file generated at
// every build (cmake/git_commit.cmake).
#include "git_commit.inc"
#include "jointsim/version_config.hpp"

namespace jointsim {

const char* version() { return JOINTSIM_VERSION; }

const char* gitCommit() { return kJointsimGitCommit; }

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace jointsim
