#pragma once
/// \file
/// The jointsim version (from CMake's project(), the one source) and the git commit of the build.

#include <string>

namespace jointsim {

/// "MAJOR.MINOR.PATCH" of this library.
const char* version();
/// The git commit the library was built from (40 hex digits, with "-dirty" when the checkout had uncommitted
/// changes), or "" when it was not built from a git checkout.
const char* gitCommit();
/// The current time in UTC as ISO 8601, e.g. "2026-11-23T09:15:02Z".
std::string utcNow();

}  // namespace jointsim
