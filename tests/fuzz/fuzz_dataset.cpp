// The HDF5 data set writer of a sweep (report::writeDataset, `jointsim batch --dataset`) over a batch output folder
// made by hand from the input: a sweep of 1 to 3 runs (explicit runs, some with faults, or a sampled design) read
// with loadSweepText, and per run a folder with a summary.json and up to two CSV logs whose text comes from the
// input; the data set's path is a plain new file, an older data set to replace, a file that is not one, a path in a
// run's folder, in a missing folder or with an overlong name. A file-size limit chosen by the input (RLIMIT_FSIZE,
// SIGXFSZ ignored) makes the writer meet a full disk at any point of the file.
//
// The writer runs HDF5 in a child process (fork); the limit is set in that child only (pthread_atfork), which is
// where the file is written, so that libFuzzer's own files and a sanitizer report of this process are never cut.
// Oracle: the call returns (the target then exists and starts with the HDF5 signature, and the summary counts every
// run) or throws a jointsim::Error (a failed call leaves the target as it was: absent, or the older file byte for
// byte); the writer never dies by a signal (a crash or sanitizer report in the child); no temporary file (NAME.tmp.PID)
// is left anywhere in the folder. Each input works in a folder of its own (mkdtemp), removed afterwards.
#include <sys/resource.h>

#include <pthread.h>
#include <signal.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/experiments/batch.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/report/dataset.hpp"

namespace {

namespace fs = std::filesystem;

// The file-size limit of the writer's child process (set between fork and the child's first write).
volatile bool g_limit_on = false;
volatile rlim_t g_limit = 0;

// In the child only: libFuzzer handles SIGXFSZ in this process (-handle_xfsz, installed after static initialisers) by
// exiting, which would run HDF5's exit handlers on a failed file; ignored, a write beyond the limit fails with EFBIG,
// as in the CLI and in Python, which ignore SIGXFSZ.
void limitChild() {
  ::signal(SIGXFSZ, SIG_IGN);
  if (!g_limit_on) return;
  struct rlimit r;
  if (::getrlimit(RLIMIT_FSIZE, &r) != 0) return;
  r.rlim_cur = g_limit < r.rlim_max ? g_limit : r.rlim_max;
  ::setrlimit(RLIMIT_FSIZE, &r);
}

const bool g_setup = [] {
  ::pthread_atfork(nullptr, nullptr, limitChild);
  return true;
}();

const std::string kSignature("\x89HDF\r\n\x1a\n", 8);

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void writeFile(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << text;
}

// The input's text after the control bytes, cut at "\n--\n" into the files of the run folders.
std::vector<std::string> sections(const std::string& text) {
  std::vector<std::string> out;
  size_t start = 0;
  for (;;) {
    const size_t at = text.find("\n--\n", start);
    out.push_back(text.substr(start, at == std::string::npos ? std::string::npos : at - start));
    if (at == std::string::npos) return out;
    start = at + 4;
  }
}

bool leftTemporaryFiles(const fs::path& dir) {
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec))
    if (it->path().filename().string().find(".tmp.") != std::string::npos) {
      std::fprintf(stderr, "fuzz_dataset: temporary file left: %s\n", it->path().c_str());
      return true;
    }
  return false;
}

}  // namespace

// Input layout (tests/fuzz/seeds/dataset/): byte 0 the sweep (runs 1 + b % 3; bit 2 a sampled design for the runs
// after the first, bit 5 Latin hypercube; bits 3-4 the faults of the first run), byte 1 the target (% 8: 0-2 a new
// file, 3 an older data set, 4 a file that is not one, 5 in a run's folder, 6 in a missing folder, 7 a long name),
// byte 2 the file-size limit (% 4: 0 none, 1 bytes 3-4 % 4096, 2 bytes 3-4, 3 bytes 3-4 x 64), bytes 3-4 its value,
// byte 5 the run names, bytes 6-8 one per run (bit 0 its folder, 1 summary.json, 2 a CSV log, 3 a second one,
// 4 run.log, bits 5-7 the logs' names); the rest the text of those files in that order, separated by lines "--".
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace jointsim;
  (void)g_setup;
  fuzz::Bytes in(data, size);
  const uint8_t shape = in.byte(), target_mode = in.byte(), limit_mode = in.byte();
  const uint16_t limit_value = in.u16();
  const uint8_t names = in.byte();
  uint8_t run_bytes[3] = {in.byte(), in.byte(), in.byte()};
  const std::vector<std::string> texts = sections(in.rest());
  size_t next_text = 0;
  auto text = [&] { return next_text < texts.size() ? texts[next_text++] : std::string(); };

  // The sweep: 1 to 3 runs; the first may carry faults (labels), the others may be a sampled design.
  const int n_runs = 1 + shape % 3;
  const bool sampled = (shape >> 2 & 1) != 0 && n_runs > 1;
  static const char* const kNames[] = {"a", "b", "run.1", "x-2", "_y", "A", "nominal", "c_3"};
  static const char* const kFaults[] = {
      "",
      "\n    faults: [{type: sensor_spike, joint: elbow_joint, value: 0.01, onset: 0.05, period: 0.05, width: 0.002}]",
      "\n    faults: [{type: gear_stiffness_scale, joint: elbow_joint, value: 0.5, onset: 0.1, progression: linear, "
      "ramp_time: 0.3}]",
      "\n    faults: [{type: sensor_bias, joint: wrist_2_joint, value: -1.0e-3}, {type: sensor_dropout, joint: "
      "elbow_joint, value: 0.01, period: 0.1, count: 2}]"};
  const fs::path dir = fuzz::makeInputDir("dataset");
  const fs::path out = dir / "out";
  std::string sweep_text = "sweep: {name: fz, experiment: \"" +
                           (fuzz::workspace() / "config/experiments/ur5_excitation.yaml").string() + "\"}\nruns:\n";
  const int explicit_runs = sampled ? 1 : n_runs;
  for (int i = 0; i < explicit_runs; ++i)
    sweep_text += std::string("  - name: ") + kNames[(names + i) % 8] + (i == 0 ? kFaults[shape >> 3 & 3] : "") + "\n";
  if (sampled)
    sweep_text += std::string("sample:\n  design: ") + ((shape >> 5 & 1) ? "latin_hypercube" : "monte_carlo") +
                  "\n  runs: " + std::to_string(n_runs - 1) + "\n  seed: " + std::to_string(names) +
                  "\n  parameters: {duration: {distribution: uniform, low: 0.1, high: 0.2}}\n";
  experiments::Sweep sweep;
  try {
    sweep = experiments::loadSweepText(sweep_text, (dir / "sweep.yaml").string());
  } catch (const Error& e) {
    std::fprintf(stderr, "fuzz_dataset: the harness's sweep was refused: %s\n%s", e.what(), sweep_text.c_str());
    __builtin_trap();
  }

  // The run folders, as a batch leaves them (or not: missing folders and files are runs not finished).
  fs::create_directories(out);
  static const char* const kLogs[] = {"ur5_excitation.csv", "log.csv",   ".csv",  "a.b.csv",
                                      "x_clamping.csv",     "UPPER.CSV", "z.csv", "y z.csv"};
  for (size_t i = 0; i < sweep.runs.size(); ++i) {
    const uint8_t r = run_bytes[i % 3];
    if ((r & 1) == 0) continue;  // no folder: pending
    const fs::path folder = out / sweep.runs[i].name;
    fs::create_directories(folder);
    if (r & 2) writeFile(folder / "summary.json", text());
    if (r & 4) writeFile(folder / kLogs[r >> 5], text());
    if (r & 8) writeFile(folder / kLogs[(r >> 5) ^ 1], text());
    if (r & 16) writeFile(folder / "run.log", "a run's output\n");
  }

  // Where the data set goes.
  fs::path target = dir / "set.h5";
  switch (target_mode % 8) {
    case 3: writeFile(target, kSignature + text()); break;  // an older data set: replaced
    case 4: writeFile(target, text()); break;               // not an HDF5 file (unless it starts like one)
    case 5: target = out / sweep.runs.front().name / "set.h5"; break;
    case 6: target = dir / "missing" / "set.h5"; break;
    case 7: target = dir / (std::string(200 + target_mode % 64, 'x') + ".h5"); break;
    default: break;
  }
  // The writer reads the run folders in its child process, whose coverage libFuzzer does not see: the same readers
  // run here first (the summaries through batchRecords, the logs), so that what the child will read guides the fuzzer.
  try {
    experiments::batchRecords(sweep, out.string());
  } catch (const Error& e) {
    fuzz::note(e);
  }
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(out, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    if (it->path().extension() != ".csv") continue;
    try {
      io::readCsv(it->path().string(), false);
    } catch (const Error& e) {
      fuzz::note(e);
    }
  }
  const bool existed = fs::exists(target, ec);
  const std::string before = existed ? readAll(target) : std::string();

  // A full disk: the child's writes fail beyond the limit (EFBIG).
  switch (limit_mode % 4) {
    case 0: g_limit_on = false; break;
    case 1: g_limit = limit_value % 4096, g_limit_on = true; break;
    case 2: g_limit = limit_value, g_limit_on = true; break;
    default: g_limit = static_cast<rlim_t>(limit_value) * 64, g_limit_on = true; break;
  }
  try {
    const report::DatasetSummary s = report::writeDataset(sweep, out.string(), target.string());
    g_limit_on = false;
    const std::string written = readAll(target);
    if (s.path != target.string() || written.compare(0, kSignature.size(), kSignature) != 0 ||
        s.runs != static_cast<int>(sweep.runs.size()) || s.runs_with_data < 0 || s.runs_with_data > s.runs ||
        s.samples < 0) {
      std::fprintf(stderr, "fuzz_dataset: a written data set that is not one (%s, %zu bytes, %d runs)\n",
                   s.path.c_str(), written.size(), s.runs);
      __builtin_trap();
    }
  } catch (const Error& e) {
    g_limit_on = false;
    fuzz::note(e);
    // The writer's own report (an Error that begins so), not text of the input quoted in another message (a log
    // cell holding "the writer ended by signal" once made this check fire on a CSV error).
    const std::string crashed = "data set " + target.string() + ": the writer ended by signal";
    if (dynamic_cast<const InputError*>(&e) == nullptr && std::string(e.what()).rfind(crashed, 0) == 0) {
      std::fprintf(stderr, "fuzz_dataset: the HDF5 writer crashed: %s\n", e.what());
      __builtin_trap();
    }
    const bool exists = fs::exists(target, ec);
    if (exists != existed || (exists && readAll(target) != before)) {
      std::fprintf(stderr, "fuzz_dataset: a failed write changed %s: %s\n", target.c_str(), e.what());
      __builtin_trap();
    }
  }
  g_limit_on = false;
  if (leftTemporaryFiles(dir)) __builtin_trap();
  fuzz::removeDir(dir);
  return 0;
}
