// The files `jointsim plot` reads: a run folder's summary.json (input bytes after an even first byte) or a
// sweep folder's manifest.csv (odd first byte), beside copies of the golden logs and two run folders a/ and
// b/, turned into a gnuplot script. Oracles besides the exception rule: every figure lands inside the
// figures folder; the script holds no control character but newlines; every line outside a datablock and
// not continuing a command starts with a command the builder writes (input text never starts a line).
#include <filesystem>
#include <regex>
#include <sstream>

#include "fuzz_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/report/plot.hpp"

namespace {
bool scriptIsWellFormed(const std::string& body) {
  static const std::regex command(
      R"(^(#.*|set .*|unset .*|plot .*|reset|outsuffix = .*|csv = '.*'|run[0-9]+ = '.*'|\$[a-z0-9]+ << EOD|)$)");
  std::istringstream in(body);
  bool block = false, continued = false;
  for (std::string line; std::getline(in, line);) {
    if (block) {
      block = line != "EOD";
    } else if (!continued) {
      if (!std::regex_match(line, command)) return false;
      block = line.size() > 6 && line.compare(line.size() - 6, 6, "<< EOD") == 0;
    }
    continued = !block && !line.empty() && line.back() == '\\';
  }
  return !block;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace jointsim;
  namespace fs = std::filesystem;
  if (size == 0) return 0;
  static const fs::path run_dir = [] {
    const fs::path source = JOINTSIM_SOURCE_DIR;
    const fs::path d = fuzz::workspace() / "run";
    fs::create_directories(d);
    for (const auto& e : fs::directory_iterator(source / "tests/golden"))
      if (e.path().extension() == ".csv") fs::copy_file(e.path(), d / e.path().filename());
    for (const char* run : {"a", "b"}) {  // the runs of the seed manifest
      fs::create_directories(d / run);
      fs::copy_file(source / "tests/golden/ur5_fall.csv", d / run / "ur5_fall.csv");
      std::ifstream seed(source / "tests/fuzz/seeds/summary/run_summary.json", std::ios::binary);
      seed.get();  // the selector byte
      std::ofstream(d / run / "summary.json", std::ios::binary) << seed.rdbuf();
    }
    return d;
  }();
  const bool sweep = (data[0] & 1) != 0;
  fs::remove(run_dir / "summary.json");
  fs::remove(run_dir / "manifest.csv");
  fuzz::writeInput(sweep ? "run/manifest.csv" : "run/summary.json", data + 1, size - 1);
  try {
    const report::PlotScript script = report::plotScript(run_dir.string());
    const fs::path figures = fs::path(script.fig_dir);
    if (figures != run_dir / "figures") __builtin_trap();
    for (const auto& f : script.figures)
      if (fs::path(f).parent_path() != figures) __builtin_trap();
    for (const char c : script.body)
      if ((static_cast<unsigned char>(c) < 0x20 && c != '\n') || c == 0x7f) __builtin_trap();
    if (!scriptIsWellFormed(script.body)) __builtin_trap();
  } catch (const Error& e) {
    fuzz::note(e);
  }
  return 0;
}
