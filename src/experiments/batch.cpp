// Running a sweep: each run in its own child process (the process pool), the manifest, resuming and shards. Reading a
// sweep file is in sweep.cpp (its faults in sweep_faults.cpp), checking one in sweep_validate.cpp.
#include "jointsim/experiments/batch.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <csignal>

#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "experiments/sweep_internal.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/common/interrupt.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/experiments/sampling.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/io/json.hpp"
#include "jointsim/io/output.hpp"
#include "jointsim/io/yaml.hpp"
#include "jointsim/sim/simulate.hpp"

namespace jointsim::experiments {
namespace {

using io::YamlValue;
namespace fs = std::filesystem;

std::string slurpFile(const fs::path& p) { return io::readBoundedFile(p.string()); }

// What a run folder's summary.json says (read with nlohmann-json; a missing or unreadable one counts as absent).
struct SummaryInfo {
  bool exists = false;
  std::string status, version, commit, started;
  double sim = 0, wall = 0, rtf = 0;
  std::vector<io::InputFile> inputs;
  std::vector<std::pair<std::string, std::uintmax_t>> outputs;  ///< files of the run's folder and their sizes
  bool has_outputs = false;
};
SummaryInfo readSummary(const fs::path& p) {
  SummaryInfo s;
  if (!io::pathExists(p.string())) return s;
  s.exists = true;
  nlohmann::ordered_json parsed;
  try {
    parsed = io::parseJson(slurpFile(p), p.string());
  } catch (const InputError&) {
    return s;  // nested too deep: unreadable
  }
  const nlohmann::ordered_json& j = parsed;
  if (!j.is_object()) return s;  // unreadable: status "" (counted as an error)
  auto text = [&](const char* key) {
    return j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : std::string();
  };
  auto number = [&](const char* key) { return j.contains(key) && j[key].is_number() ? j[key].get<double>() : 0.0; };
  s.status = text("status");
  s.version = text("jointsim_version");
  s.commit = text("git_commit");
  s.started = text("started_utc");
  s.sim = number("sim_time_s");
  s.wall = number("wall_time_s");
  s.rtf = number("real_time_factor");
  if (j.contains("inputs") && j["inputs"].is_array())
    for (const auto& in : j["inputs"])
      if (in.is_object() && in.contains("path") && in.contains("hash") && in["path"].is_string() &&
          in["hash"].is_string())
        s.inputs.push_back({in["path"].get<std::string>(), in["hash"].get<std::string>(), 0});
  if (j.contains("outputs") && j["outputs"].is_array()) {
    s.has_outputs = true;
    for (const auto& out : j["outputs"])
      if (out.is_object() && out.contains("file") && out["file"].is_string() && out.contains("bytes") &&
          out["bytes"].is_number_unsigned())
        s.outputs.emplace_back(out["file"].get<std::string>(), out["bytes"].get<std::uintmax_t>());
      else
        s.has_outputs = false;  // unreadable: not reused
  }
  return s;
}

// The outputs of a finished run are still there as written: each file its summary lists exists in the run's folder
// with the size it had (a deleted or emptied log makes the run run again instead of a data set without its data).
bool outputsIntact(const SummaryInfo& s, const fs::path& folder) {
  if (!s.has_outputs || s.outputs.empty()) return false;
  for (const auto& [file, bytes] : s.outputs) {
    if (file.empty() || file.find('/') != std::string::npos || file == "." || file == "..") return false;
    std::error_code ec;
    if (fs::file_size(folder / file, ec) != bytes || ec) return false;
  }
  return true;
}

// The inputs a finished run read still have the content they had: every file listed in its summary hashes to
// the recorded value. A run without recorded inputs (an older summary) does not count as current.
// `hashes` caches the hash of each file for one batch (a sweep's runs read the same few files).
bool inputsUnchanged(const SummaryInfo& s, std::map<std::string, std::string>& hashes) {
  if (s.inputs.empty()) return false;
  for (const auto& in : s.inputs) {
    auto it = hashes.find(in.path);
    if (it == hashes.end()) it = hashes.emplace(in.path, io::fileHash(in.path)).first;
    if (it->second != in.hash) return false;
  }
  return true;
}

// What a run's results depend on besides its input files, as stored in <run>/run.settings: the base experiment
// file and the run's overrides and faults. A finished run is reused only if its stamp matches and its inputs
// are unchanged (docs/batch.md).
}  // namespace

std::string runSettings(const Sweep& sweep, const BatchRun& run) {
  // Each part a JSON string, one per list entry: unambiguous whatever the values hold (joined by "; ", an override
  // value "x; log_rate=50" read like a second override log_rate=50, and a stale result was reused).
  nlohmann::json overrides = nlohmann::json::array(), faults = nlohmann::json::array();
  for (const std::string& o : run.overrides) overrides.push_back(o);
  for (const systems::Fault& f : run.faults) faults.push_back(systems::describe(f));
  constexpr auto kReplace = nlohmann::json::error_handler_t::replace;
  return "experiment: " + nlohmann::json(sweep.experiment).dump(-1, ' ', false, kReplace) +
         "\noverrides: " + overrides.dump(-1, ' ', false, kReplace) +
         "\nfaults: " + faults.dump(-1, ' ', false, kReplace) + "\n";
}

namespace {

// An RFC 4180 field: quoted, with quotes doubled.
std::string csvQuote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}
// An RFC 4180 field, quoted when it has to be (a comma, a quote, a line break; e.g. a joint name or a summary's
// version string), plain otherwise.
std::string csvField(const std::string& s) { return s.find_first_of(",\"\r\n") == std::string::npos ? s : csvQuote(s); }

void writeManifest(const std::string& path, const std::vector<BatchRecord>& records) {
  std::ostringstream os;
  os << "run,status,wall_time_s,sim_time_s,real_time_factor,output_dir,overrides,jointsim_version,git_commit,started_utc,"
        "inputs,fault_type,fault_joint,fault_severity,fault_onset_s,design,seed\n";
  os.precision(6);
  for (const auto& r : records)
    os << csvField(r.run) << ',' << csvField(r.status) << ',' << r.wall_time_s << ',' << r.sim_time_s << ','
       << r.real_time_factor << ',' << csvField(r.output_dir) << ',' << csvQuote(r.overrides) << ','
       << csvField(r.jointsim_version) << ',' << csvField(r.git_commit) << ',' << csvField(r.started_utc) << ','
       << csvQuote(r.inputs) << ',' << csvField(r.fault_type) << ',' << csvField(r.fault_joint) << ','
       << csvField(r.fault_severity) << ',' << csvField(r.fault_onset_s) << ',' << csvField(r.design) << ','
       << csvField(r.seed) << '\n';
  if (!os) throw Error(path + ": cannot format the manifest (out of memory?)");
  io::writeFileAtomically(path, os.str());  // checks every write; the old manifest stays on a failure
}

// The batch's hold on its output folder: an exclusive flock on <dir>/.jointsim-batch.lock for a whole-sweep batch
// or --collect, a shared one for a shard (the shards of a job array write disjoint run folders at the same time),
// and an exclusive one on the manifest it writes (<manifest>.lock). A second batch into the same folder (or the
// same shard) is refused at once instead of deleting the first one's files. Locks end with the process
// (also on kill -9); flock works across the nodes of an NFS (v4) file system.
class FolderLock {
 public:
  FolderLock(const std::string& dir, const std::string& manifest, bool shard)
      : folder_((std::filesystem::path(dir) / ".jointsim-batch.lock").string(), !shard,
                busy(dir, ".jointsim-batch.lock")),
        manifest_(manifest + ".lock", true, busy(dir, std::filesystem::path(manifest).filename().string() + ".lock")) {}

 private:
  static std::string busy(const std::string& dir, const std::string& file) {
    return dir + ": another jointsim batch is writing into this folder (it holds " + file +
           "); wait for it to end, or give this one another output folder (-o)";
  }
  io::FileLock folder_, manifest_;
};

// Removes temporary files ("NAME.tmp.PID") left in `folder` by a process that was killed (kill -9, a node lost)
// while writing; the caller holds the lock that makes it the only writer there.
void removeLeftovers(const std::string& folder, const std::string& prefix = "") {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(folder, ec)) {
    const std::string f = e.path().filename().string();
    if (f.find(".tmp.") != std::string::npos && f.rfind(prefix, 0) == 0 && e.is_regular_file(ec))
      fs::remove(e.path(), ec);
  }
}

// When to rewrite the manifest while runs finish: at least 10 times as much time between rewrites as the last one
// took, so that rewriting costs at most ~10 % of the batch whatever the size of the sweep (a 100,000-run sweep once
// spent its time rewriting a 20 MB file after every run); always at the start and at the end.
class ManifestPacer {
 public:
  bool due(double now_s) const { return now_s - last_end_s_ >= 10.0 * last_cost_s_; }
  void wrote(double start_s, double end_s) {
    last_cost_s_ = end_s - start_s;
    last_end_s_ = end_s;
    ++writes_;
  }
  int writes() const { return writes_; }

 private:
  double last_end_s_ = 0.0, last_cost_s_ = 0.0;
  int writes_ = 0;
};

std::string outputDir(const Sweep& s, const BatchOptions& o) { return batchOutputDir(s, o.output_dir); }

// The record of a run from its folder (status "pending" when there is no summary).
BatchRecord recordFromFolder(const BatchRun& run, const std::string& dir) {
  BatchRecord r;
  r.run = run.name;
  r.output_dir = run.name;
  r.overrides = run.describe();
  for (const systems::Fault& f : run.faults) {
    const std::string sep = r.fault_type.empty() ? "" : ";";
    r.fault_type += sep + systems::toString(f.type);
    r.fault_joint += sep + f.joint;
    r.fault_severity += sep + formatShortest(f.value);
    r.fault_onset_s += sep + formatShortest(f.onset);
  }
  r.design = run.design;
  if (run.seed >= 0) r.seed = std::to_string(run.seed);
  const SummaryInfo s = readSummary(fs::path(dir) / run.name / "summary.json");
  r.status = s.exists ? (s.status.empty() ? "error" : s.status) : "pending";
  r.sim_time_s = s.sim;
  r.wall_time_s = s.wall;
  r.real_time_factor = s.rtf;
  r.jointsim_version = s.version;
  r.git_commit = s.commit;
  r.started_utc = s.started;
  for (const auto& in : s.inputs) r.inputs += (r.inputs.empty() ? "" : ";") + in.path + "=" + in.hash;
  return r;
}

// Child process: runs one experiment with its output in `folder`, stdout/stderr to folder/run.log.
[[noreturn]] void childRun(const Sweep& sweep, const BatchRun& run, const std::string& folder) {
  // The parent's signal dispositions are inherited; a host's own (Python's) would only set a flag nobody reads here,
  // and the host's poll of the forking thread must not be asked from this process (it would take Python's lock).
  forgetStopPolls();
  installStopSignalHandlers();
  const std::string log = (fs::path(folder) / "run.log").string();
  // Truncate once, then append from both streams so that their writes do not overwrite each other.
  if (std::FILE* f = std::fopen(log.c_str(), "w")) std::fclose(f);
  if (!std::freopen(log.c_str(), "a", stdout) || !std::freopen(log.c_str(), "a", stderr)) _exit(2);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  int code = 0;
  try {
    RunOptions o;
    o.output_dir = folder;
    o.overrides = run.overrides;
    o.faults = run.faults;
    const RunReport r = runExperimentFile(sweep.experiment, o);
    std::printf("%s: %s, simulated %g s in %g s (real-time factor %g)\n", run.name.c_str(), r.status.c_str(),
                r.sim_time_s, r.wall_time_s, r.real_time_factor);
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    code = 2;
  } catch (const sim::Interrupted& e) {
    std::fprintf(stderr, "interrupted: %s\n", e.what());
    code = 128 + (e.signal() > 0 ? e.signal() : SIGINT);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "failed: %s\n", e.what());
    code = 1;
  }
  std::fflush(nullptr);
  _exit(code);
}

}  // namespace

std::vector<size_t> shardRuns(size_t n_runs, int index, int count) {
  if (count < 1 || index < 0 || index >= count)
    throw InputError("shard: expected I/N with 0 <= I < N, got " + std::to_string(index) + "/" + std::to_string(count));
  std::vector<size_t> out;
  for (size_t i = static_cast<size_t>(index); i < n_runs; i += static_cast<size_t>(count)) out.push_back(i);
  return out;
}

BatchResult runBatch(const Sweep& sweep, const BatchOptions& options) {
  if (options.jobs < 1)
    throw InputError("jobs: expected at least 1 job at a time, got " + std::to_string(options.jobs));
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<size_t> mine = shardRuns(sweep.runs.size(), options.shard_index, options.shard_count);
  const std::string dir = outputDir(sweep, options);
  io::createDirectories(dir);  // after the checks: a bad shard leaves nothing behind
  BatchResult res;
  res.manifest_path =
      (fs::path(dir) / (options.shard_count > 1 ? "manifest.shard-" + std::to_string(options.shard_index) + "-of-" +
                                                      std::to_string(options.shard_count) + ".csv"
                                                : std::string("manifest.csv")))
          .string();
  const FolderLock lock(dir, res.manifest_path, options.shard_count > 1);
  removeLeftovers(dir, fs::path(res.manifest_path).filename().string() + ".tmp.");
  std::map<std::string, std::string> hashes;
  std::vector<size_t> queue;
  for (size_t k = 0; k < mine.size(); ++k) {
    if (const int sig = stopRequested()) {  // reading the folders of a large sweep takes a while
      res.interrupted = sig;
      return res;
    }
    const BatchRun& run = sweep.runs[mine[k]];
    BatchRecord r = recordFromFolder(run, dir);
    const fs::path folder = fs::path(dir) / run.name;
    bool same = false;
    if (r.status == "ok") {
      const SummaryInfo summary = readSummary(folder / "summary.json");
      same = slurpFile(folder / "run.settings") == runSettings(sweep, run) && inputsUnchanged(summary, hashes) &&
             outputsIntact(summary, folder);
      if (same) removeLeftovers(folder.string());
    }
    if (r.status == "ok" && same) {
      r.skipped = true;
      ++res.skipped;
      ++res.ok;
    } else {
      r.status = "pending";
      queue.push_back(k);
    }
    res.records.push_back(r);
  }
  ManifestPacer pacer;
  const auto seconds = [t0] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  auto rewrite = [&](bool always) {
    const double start = seconds();
    if (!always && !pacer.due(start)) return;
    writeManifest(res.manifest_path, res.records);
    pacer.wrote(start, seconds());
  };
  rewrite(true);
  // Progress line (a terminal only): runs done, failed, skipped, running, and the time left, estimated from the wall
  // time of the runs finished in this call (skipped runs excluded) spread over the jobs.
  double finished_wall = 0.0;
  int finished = 0;
  const size_t to_run = queue.size();
  std::string last_line;
  auto last_print = std::chrono::steady_clock::now();
  auto progress = [&](int running) {
    if (!options.progress) return;
    std::string left;
    if (finished > 0) {
      const double per_run = finished_wall / finished;
      const size_t remaining_runs = to_run - static_cast<size_t>(finished);
      const double remaining = static_cast<double>(remaining_runs) * per_run /
                               std::max(1, std::min(options.jobs, static_cast<int>(remaining_runs)));
      left = ", about " + formatDuration(remaining) + " left";
    }
    char line[512];
    std::snprintf(line, sizeof line, "%zu/%zu done (%d failed, %d skipped), %d running%s",
                  static_cast<size_t>(res.ok + res.failed), res.records.size(), res.failed, res.skipped, running,
                  left.c_str());
    // A new line when something changed; the same one again at most twice a second.
    const auto now = std::chrono::steady_clock::now();
    if (line == last_line && std::chrono::duration<double>(now - last_print).count() < 0.5) return;
    last_line = line;
    last_print = now;
    std::fprintf(stderr, "\r[batch %s] %s   ", sweep.name.c_str(), line);
    std::fflush(stderr);
  };
  struct Active {
    size_t k;
    std::chrono::steady_clock::time_point start;
  };
  std::map<pid_t, Active> active;
  size_t next = 0;
  progress(0);
  bool forwarded = false;
  while ((next < queue.size() && !stopRequested()) || !active.empty()) {
    // A stop request (SIGINT/SIGTERM to the batch): no new runs; the running ones get the signal and end with an
    // "interrupted" summary, which resume treats as not done.
    if (const int sig = stopRequested(); sig && !forwarded) {
      for (const auto& [p, a] : active) ::kill(p, sig > 0 ? sig : SIGINT);
      forwarded = true;
    }
    while (next < queue.size() && !stopRequested() && static_cast<int>(active.size()) < options.jobs) {
      const size_t k = queue[next++];
      const BatchRun& run = sweep.runs[mine[k]];
      const std::string folder = (fs::path(dir) / run.name).string();
      io::createDirectories(folder);
      // Stale results of an earlier attempt must not be mistaken for this one's.
      std::error_code ec;
      for (const auto& e : fs::directory_iterator(folder, ec)) {
        const std::string f = e.path().filename().string();
        if (e.path().extension() == ".csv" || f == "summary.json" || f.find(".tmp.") != std::string::npos)
          fs::remove(e.path(), ec);
      }
      io::writeFileAtomically((fs::path(folder) / "run.settings").string(), runSettings(sweep, run));
      std::fflush(nullptr);
      const pid_t pid = ::fork();
      if (pid < 0) {
        res.records[k].status = "error";
        ++res.failed;
        std::fprintf(stderr, "jointsim batch: cannot start run '%s' (fork failed)\n", run.name.c_str());
        continue;
      }
      if (pid == 0) childRun(sweep, run, folder);
      active[pid] = {k, std::chrono::steady_clock::now()};
      res.records[k].status = "running";
    }
    progress(static_cast<int>(active.size()));
    if (active.empty()) continue;
    int status = 0;
    // Not a blocking wait: a stop request of this thread (a host's StopPoll, e.g. Ctrl-C in Python) must be seen
    // while runs are going. Only this batch's own runs are waited for (a host may have children of its own).
    pid_t pid = 0;
    for (const auto& entry : active) {
      const pid_t got = ::waitpid(entry.first, &status, WNOHANG);
      if (got < 0 && errno == EINTR) break;
      if (got < 0) {  // not ours to wait for any more (reaped elsewhere): it ended without a known status
        status = -1;
        pid = entry.first;
        break;
      }
      if (got > 0) {
        pid = got;
        break;
      }
    }
    if (pid == 0) {
      struct timespec pause {};
      pause.tv_nsec = 20'000'000;  // 20 ms
      ::nanosleep(&pause, nullptr);
      continue;
    }
    const auto it = active.find(pid);
    if (it == active.end()) continue;
    const Active a = it->second;
    active.erase(it);
    const BatchRun& run = sweep.runs[mine[a.k]];
    BatchRecord r = recordFromFolder(run, dir);
    r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - a.start).count();
    finished_wall += r.wall_time_s;
    ++finished;
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0 && r.status == "ok") {
      ++res.ok;
    } else {
      if (r.status != "failed" && r.status != "interrupted") r.status = "error";  // bad input, crash: see run.log
      if (r.status == "error" && !io::pathExists((fs::path(dir) / run.name / "summary.json").string())) {
        // The run ended before it could write its summary (bad input found when loading, a crash): say so in the
        // folder, so that --collect (e.g. after the shards of a job array) reports it as an error, not as pending.
        nlohmann::ordered_json j;
        j["status"] = "error";
        j["reason"] = WIFSIGNALED(status)
                          ? "killed by signal " + std::to_string(WTERMSIG(status)) + "; see run.log"
                          : "exit status " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                                " before a summary was written; see run.log";
        io::writeFileAtomically((fs::path(dir) / run.name / "summary.json").string(), j.dump(2) + "\n");
      }
      ++res.failed;
    }
    res.records[a.k] = r;
    rewrite(false);
  }
  rewrite(true);
  res.manifest_writes = pacer.writes();
  progress(0);
  if (options.progress) std::fputc('\n', stderr);
  res.interrupted = stopRequested();
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

std::string batchOutputDir(const Sweep& sweep, const std::string& output_dir) {
  return output_dir.empty() ? (fs::path("out") / sweep.name).string() : output_dir;
}

std::vector<BatchRecord> batchRecords(const Sweep& sweep, const std::string& output_dir) {
  const std::string dir = batchOutputDir(sweep, output_dir);
  std::vector<BatchRecord> out;
  for (const auto& run : sweep.runs) out.push_back(recordFromFolder(run, dir));
  return out;
}

BatchResult collectBatch(const Sweep& sweep, const BatchOptions& options) {
  const std::string dir = outputDir(sweep, options);
  BatchResult res;
  res.manifest_path = (fs::path(dir) / "manifest.csv").string();
  io::createDirectories(dir);
  const FolderLock lock(dir, res.manifest_path, false);
  removeLeftovers(dir, "manifest.csv.tmp.");
  for (const BatchRun& run : sweep.runs) {
    if (const int sig = stopRequested()) {  // nothing written: the old manifest stays
      res.interrupted = sig;
      return res;
    }
    BatchRecord r = recordFromFolder(run, dir);
    if (r.status == "ok")
      ++res.ok;
    else if (r.status != "pending")
      ++res.failed;
    res.records.push_back(r);
  }
  writeManifest(res.manifest_path, res.records);
  res.manifest_writes = 1;
  return res;
}
}  // namespace jointsim::experiments
