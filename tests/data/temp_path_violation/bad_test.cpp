// Fixture of the check cmake/check_test_temp_paths.cmake (never compiled): every way a test could name a fixed
// temporary path, one per line, and the lines the check must accept. The CTest test check_test_temp_paths_fixture
// expects exactly the findings at lines 8, 9, 10, 11 and 12 (edit it when this file changes).
#include <cstdio>
#include <filesystem>

void bad() {
  const auto dir = std::filesystem::temp_directory_path() / "jointsim_shared";
  const char* literal = "/tmp/jointsim_shared.csv";
  const char* other = '/tmp/x' == 0 ? "" : "";
  char name[L_tmpnam];
  const char* base = P_tmpdir;
}

void fine() {
  const char* hostile = "/tmp/evil";  // tmp-path-ok: hostile input, never written
  const char* no_slash = "/tmp";
  const char* inside = "build/tmp/x";
}
