#include "jointsim/report/dataset.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include <fcntl.h>
#include <hdf5.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include "jointsim/common/error.hpp"
#include "jointsim/common/interrupt.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/common/version.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/io/output.hpp"
#include "jointsim/sim/simulate.hpp"

namespace jointsim::report {
namespace {

namespace fs = std::filesystem;

// The system's reason for the innermost HDF5 failure, e.g. "No space left on device": HDF5's file drivers record
// "..., errno = 28, error message = 'No space left on device', ..." on the error stack. Empty when there is none.
std::string hdf5Reason() {
  std::string reason;
  auto visit = [](unsigned, const H5E_error2_t* e, void* data) -> herr_t {
    const std::string desc = e->desc != nullptr ? e->desc : "";
    const std::string key = "error message = '";
    if (const size_t at = desc.find(key); at != std::string::npos) {
      const size_t end = desc.find('\'', at + key.size());
      *static_cast<std::string*>(data) = desc.substr(at + key.size(), end - at - key.size());
    }
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, visit, &reason);
  return reason;
}

[[noreturn]] void hdf5Failure(const std::string& what) {
  const std::string reason = hdf5Reason();
  throw Error("HDF5: cannot " + what + (reason.empty() ? "" : ": " + reason));
}

// An HDF5 identifier closed by its own close function when it goes out of scope; a negative id is HDF5's error.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t), const std::string& what) : id_(id), close_(close) {
    if (id_ < 0) hdf5Failure(what);
  }
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  operator hid_t() const { return id_; }
  /// Closes now and reports a failure (the close of a file writes what is still cached).
  void close(const std::string& what) {
    const hid_t id = id_;
    id_ = -1;
    check(close_(id), what);
  }

 private:
  static void check(herr_t status, const std::string& what) {
    if (status < 0) hdf5Failure(what);
  }
  hid_t id_;
  herr_t (*close_)(hid_t);
};

void check(herr_t status, const std::string& what) {
  if (status < 0) hdf5Failure(what);
}

// A variable-length UTF-8 string attribute (h5py reads it as str).
void attribute(hid_t object, const char* name, const std::string& value) {
  const Handle type(H5Tcopy(H5T_C_S1), H5Tclose, "copy a string type");
  check(H5Tset_size(type, H5T_VARIABLE), "size a string type");
  check(H5Tset_cset(type, H5T_CSET_UTF8), "set UTF-8");
  const Handle space(H5Screate(H5S_SCALAR), H5Sclose, "create a scalar space");
  const Handle attr(H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                    std::string("create attribute ") + name);
  const char* text = value.c_str();
  check(H5Awrite(attr, type, &text), std::string("write attribute ") + name);
}

template <typename T>
void numberAttribute(hid_t object, const char* name, T value) {
  const hid_t file_type = std::is_floating_point_v<T> ? H5T_IEEE_F64LE : H5T_STD_I64LE;
  const hid_t mem_type = std::is_floating_point_v<T> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_LLONG;
  const Handle space(H5Screate(H5S_SCALAR), H5Sclose, "create a scalar space");
  const Handle attr(H5Acreate2(object, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                    std::string("create attribute ") + name);
  if constexpr (std::is_floating_point_v<T>) {
    const double v = value;
    check(H5Awrite(attr, mem_type, &v), std::string("write attribute ") + name);
  } else {
    const long long v = value;
    check(H5Awrite(attr, mem_type, &v), std::string("write attribute ") + name);
  }
}

// A 1-D float64 data set, chunked and compressed (shuffle + deflate) when long enough to gain from it.
void doubles(hid_t group, const std::string& name, const double* data, hsize_t n, const std::string& unit) {
  const Handle space(H5Screate_simple(1, &n, nullptr), H5Sclose, "create a data space");
  const Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "create a property list");
  if (n >= 64) {
    const hsize_t chunk = std::min<hsize_t>(n, 16384);
    check(H5Pset_chunk(dcpl, 1, &chunk), "set chunks");
    check(H5Pset_shuffle(dcpl), "set shuffle");
    check(H5Pset_deflate(dcpl, 4), "set deflate");
  }
  const Handle set(H5Dcreate2(group, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT), H5Dclose,
                   "create data set " + name);
  if (n > 0) check(H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), "write data set " + name);
  attribute(set, "unit", unit);
}

// HDF5 link names may not contain '/' and '.' alone is the group itself.
std::string linkName(const std::string& s) {
  std::string out = s;
  for (char& c : out)
    if (c == '/') c = '_';
  return out == "." || out.empty() ? "_" + out : out;
}

// Fixed-length string fields of the label table: each as long as its longest value (at least 1 byte).
struct LabelTable {
  std::vector<std::string> run, status, type, joint, design;
  std::vector<double> severity, onset;
  std::vector<int> count;
  std::vector<long long> seed;
};

size_t longest(const std::vector<std::string>& v) {
  size_t n = 1;
  for (const auto& s : v) n = std::max(n, s.size());
  return n;
}

void writeLabels(hid_t file, const LabelTable& t) {
  const std::vector<std::pair<const char*, const std::vector<std::string>*>> strings = {
      {"run", &t.run}, {"status", &t.status}, {"fault_type", &t.type}, {"fault_joint", &t.joint}};
  // Row layout in memory: the string fields, then the numbers (packed; HDF5 converts to the file type).
  std::vector<size_t> width;
  size_t offset = 0;
  std::vector<size_t> offsets;
  for (const auto& [name, v] : strings) {
    width.push_back(longest(*v));
    offsets.push_back(offset);
    offset += width.back();
  }
  const size_t o_sev = offset, o_onset = o_sev + sizeof(double), o_count = o_onset + sizeof(double),
               o_design = o_count + sizeof(int), w_design = longest(t.design), o_seed = o_design + w_design,
               row = o_seed + sizeof(long long);
  const Handle type(H5Tcreate(H5T_COMPOUND, row), H5Tclose, "create the label type");
  std::vector<std::unique_ptr<Handle>> string_types;  // closed when the table is written (or on an error)
  auto stringType = [&](size_t n) -> hid_t {
    string_types.push_back(std::make_unique<Handle>(H5Tcopy(H5T_C_S1), H5Tclose, "copy a string type"));
    const hid_t s = *string_types.back();
    check(H5Tset_size(s, n), "size a string field");
    check(H5Tset_strpad(s, H5T_STR_NULLPAD), "pad a string field");
    check(H5Tset_cset(s, H5T_CSET_UTF8), "set UTF-8");
    return s;
  };
  for (size_t i = 0; i < strings.size(); ++i)
    check(H5Tinsert(type, strings[i].first, offsets[i], stringType(width[i])), "insert a label field");
  check(H5Tinsert(type, "fault_severity", o_sev, H5T_NATIVE_DOUBLE), "insert fault_severity");
  check(H5Tinsert(type, "fault_onset_s", o_onset, H5T_NATIVE_DOUBLE), "insert fault_onset_s");
  check(H5Tinsert(type, "fault_count", o_count, H5T_NATIVE_INT), "insert fault_count");
  check(H5Tinsert(type, "design", o_design, stringType(w_design)), "insert design");
  check(H5Tinsert(type, "seed", o_seed, H5T_NATIVE_LLONG), "insert seed");
  const size_t n = t.run.size();
  std::vector<char> buffer(n * row, '\0');
  for (size_t r = 0; r < n; ++r) {
    char* p = buffer.data() + r * row;
    for (size_t i = 0; i < strings.size(); ++i) {
      const std::string& s = (*strings[i].second)[r];
      std::memcpy(p + offsets[i], s.data(), s.size());
    }
    std::memcpy(p + o_sev, &t.severity[r], sizeof(double));
    std::memcpy(p + o_onset, &t.onset[r], sizeof(double));
    std::memcpy(p + o_count, &t.count[r], sizeof(int));
    std::memcpy(p + o_design, t.design[r].data(), t.design[r].size());
    std::memcpy(p + o_seed, &t.seed[r], sizeof(long long));
  }
  const hsize_t dims = n;
  const Handle space(H5Screate_simple(1, &dims, nullptr), H5Sclose, "create the label space");
  const Handle set(H5Dcreate2(file, "labels", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
                   "create /labels");
  if (n > 0) check(H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data()), "write /labels");
}

// Removes the temporary file unless committed.
struct TemporaryFile {
  std::string path;
  bool keep = false;
  ~TemporaryFile() {
    if (!keep) std::remove(path.c_str());
  }
};

}  // namespace

void checkDatasetPath(const std::string& path) {
  if (path.empty()) throw InputError("data set: expected a file name (FILE.h5)");
  if (path.find('\0') != std::string::npos) throw InputError("data set: the file name contains a NUL byte");
  const fs::path folder = fs::path(path).parent_path();
  std::error_code ec;
  if (!folder.empty() && !fs::is_directory(folder, ec))
    throw InputError("data set " + path + ": folder '" + folder.string() + "' does not exist");
  if (fs::is_directory(path, ec)) throw InputError("data set " + path + ": is a folder, expected a file name");
  // The file is written as NAME.tmp.PID beside the target: that name must fit the usual 255-byte limit as well.
  const std::string name = fs::path(path).filename().string();
  constexpr size_t kMaxName = 255 - std::char_traits<char>::length(".tmp.") - 10;
  if (name.size() > kMaxName)
    throw InputError("data set " + path + ": a file name of " + std::to_string(name.size()) +
                     " bytes is too long (at most " + std::to_string(kMaxName) +
                     ", room for the temporary name written beside it)");
  if (io::pathExists(path)) {
    // Never replace something that is not a data set (e.g. a run's log given by mistake).
    std::FILE* f = std::fopen(path.c_str(), "rb");
    char head[8] = {};
    const size_t n = f != nullptr ? std::fread(head, 1, sizeof head, f) : 0;
    if (f != nullptr) std::fclose(f);
    if (n != sizeof head || std::memcmp(head, "\x89HDF\r\n\x1a\n", sizeof head) != 0)
      throw InputError("data set " + path + ": the file exists and is not an HDF5 file; refusing to replace it");
  }
  // Can a file be created there at all (a read-only folder, a full or read-only file system)? Found now, before
  // any run, not after all of them.
  const std::string probe = io::temporaryName(path);
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
  if (fd < 0 && errno != EEXIST)
    throw InputError("data set " + path + ": cannot create a file in folder '" +
                     (folder.empty() ? std::string(".") : folder.string()) + "': " + std::strerror(errno));
  if (fd >= 0) {
    ::close(fd);
    ::unlink(probe.c_str());
  }
}

void checkDatasetPath(const experiments::Sweep& sweep, const std::string& output_dir, const std::string& path) {
  checkDatasetPath(path);
  // Not inside a run's folder (a batch clears its run folders when it runs them again).
  std::error_code ec;
  const fs::path dir = fs::weakly_canonical(experiments::batchOutputDir(sweep, output_dir), ec);
  const fs::path parent = fs::weakly_canonical(fs::absolute(path).parent_path(), ec);
  if (parent.parent_path() == dir)
    for (const experiments::BatchRun& run : sweep.runs)
      if (parent.filename() == run.name)
        throw InputError("data set " + path + ": is inside the folder of run '" + run.name +
                         "'; write it elsewhere (e.g. beside the batch's manifest)");
}

namespace {

// Writes the HDF5 file `tmp` (in the child process of writeDataset).
DatasetSummary writeDatasetFile(const experiments::Sweep& sweep, const std::string& dir, const std::string& tmp_path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors become exceptions, not HDF5's stack dumps on stderr
  const std::vector<experiments::BatchRecord> records = experiments::batchRecords(sweep, dir);
  DatasetSummary summary;
  struct {
    std::string path;
  } tmp{tmp_path};
  {
    // The HDF5 1.10 file format: compact object headers and single-chunk indexes (several thousand small data sets per file).
    const Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "create a file access list");
    check(H5Pset_libver_bounds(fapl, H5F_LIBVER_V110, H5F_LIBVER_V110), "set the file format version");
    Handle file(H5Fcreate(tmp.path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), H5Fclose, "create " + tmp.path);
    attribute(file, "format", "jointsim-dataset");
    numberAttribute(file, "format_version", 1L);
    attribute(file, "sweep", sweep.name);
    attribute(file, "sweep_file", sweep.file);
    attribute(file, "experiment", sweep.experiment);
    attribute(file, "jointsim_version", version());
    attribute(file, "created_utc", utcNow());
    numberAttribute(file, "runs", static_cast<long>(records.size()));

    LabelTable labels;
    const Handle runs(H5Gcreate2(file, "runs", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create /runs");
    for (size_t i = 0; i < records.size(); ++i) {
      const experiments::BatchRecord& r = records[i];
      const experiments::BatchRun& run = sweep.runs[i];
      labels.run.push_back(r.run);
      labels.status.push_back(r.status);
      labels.type.push_back(r.fault_type);
      labels.joint.push_back(r.fault_joint);
      labels.severity.push_back(run.faults.empty() ? std::nan("") : run.faults.front().value);
      labels.onset.push_back(run.faults.empty() ? std::nan("") : run.faults.front().onset);
      labels.count.push_back(static_cast<int>(run.faults.size()));
      labels.design.push_back(r.design);
      labels.seed.push_back(run.seed);

      const Handle group(H5Gcreate2(runs, linkName(r.run).c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
                         "create group /runs/" + r.run);
      attribute(group, "status", r.status);
      attribute(group, "settings", experiments::runSettings(sweep, run));
      attribute(group, "overrides", r.overrides);
      std::string faults;
      for (const auto& f : run.faults) faults += (faults.empty() ? "" : "; ") + systems::describe(f);
      attribute(group, "faults", faults);
      attribute(group, "inputs", r.inputs);
      attribute(group, "jointsim_version", r.jointsim_version);
      attribute(group, "git_commit", r.git_commit);
      attribute(group, "started_utc", r.started_utc);
      numberAttribute(group, "sim_time_s", r.sim_time_s);
      numberAttribute(group, "wall_time_s", r.wall_time_s);
      attribute(group, "fault_type", r.fault_type);
      attribute(group, "fault_joint", r.fault_joint);
      attribute(group, "fault_severity", r.fault_severity);
      attribute(group, "fault_onset_s", r.fault_onset_s);
      attribute(group, "design", r.design);
      numberAttribute(group, "seed", run.seed);
      const fs::path folder = fs::path(dir) / run.name;
      const fs::path summary_file = folder / "summary.json";
      attribute(group, "summary_json",
                io::pathExists(summary_file.string()) ? io::readBoundedFile(summary_file.string()) : std::string());
      // The run's log: the CSV files of its folder (one per experiment; several are stored in subgroups).
      std::vector<fs::path> logs;
      std::error_code ec;
      for (const auto& e : fs::directory_iterator(folder, ec))
        if (e.path().extension() == ".csv") logs.push_back(e.path());
      std::sort(logs.begin(), logs.end());
      std::string columns;
      for (const fs::path& log : logs) {
        const io::CsvTable table = io::readCsv(log.string(), false);
        std::unique_ptr<Handle> sub;
        hid_t target = group;
        if (logs.size() > 1) {
          sub = std::make_unique<Handle>(H5Gcreate2(group, linkName(log.stem().string()).c_str(), H5P_DEFAULT,
                                                    H5P_DEFAULT, H5P_DEFAULT),
                                         H5Gclose, "create a group for " + log.string());
          target = *sub;
        }
        const Eigen::Index n = table.rows();
        for (size_t c = 0; c < table.header.size(); ++c) {
          const auto [name, unit] = splitColumn(table.header[c]);
          // Eigen stores the table by columns: each column is contiguous.
          doubles(target, linkName(name), table.data.col(static_cast<Eigen::Index>(c)).data(), static_cast<hsize_t>(n),
                  unit);
          columns += (columns.empty() ? "" : ",") + name;
        }
        summary.samples += static_cast<long>(n);
      }
      attribute(group, "columns", columns);
      if (!logs.empty()) ++summary.runs_with_data;
      ++summary.runs;
    }
    writeLabels(file, labels);
    check(H5Fflush(file, H5F_SCOPE_GLOBAL), "flush " + tmp.path);
    file.close("close " + tmp.path);  // the file is complete on disk
  }
  return summary;
}

// Reads all of `fd` (the child's report), or stops early on a stop request; false when a stop was requested.
bool readReport(int fd, std::string& out) {
  char buf[4096];
  for (;;) {
    if (stopRequested()) return false;
    struct pollfd p {
      fd, POLLIN, 0
    };
    const int r = ::poll(&p, 1, 100);
    if (r < 0 && errno != EINTR) return true;
    if (r <= 0) continue;
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return true;
    out.append(buf, static_cast<size_t>(n));
  }
}

void writeAll(int fd, const std::string& s) {
  size_t done = 0;
  while (done < s.size()) {
    const ssize_t n = ::write(fd, s.data() + done, s.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += static_cast<size_t>(n);
  }
}

}  // namespace

DatasetSummary writeDataset(const experiments::Sweep& sweep, const std::string& output_dir, const std::string& path) {
  checkDatasetPath(sweep, output_dir, path);
  const std::string dir = experiments::batchOutputDir(sweep, output_dir);
  TemporaryFile tmp{io::temporaryName(path)};
  // HDF5 is used in a child process of its own: after a failed write (a full disk) HDF5 1.10 keeps the half-closed
  // file in its tables and crashes when the process exits (H5F__close_cb at exit), which would take a host process
  // (Python) with it. The child reports "ok RUNS WITH_DATA SAMPLES" or "input MESSAGE" / "error MESSAGE" on a pipe.
  int fds[2];
  if (::pipe(fds) != 0) throw Error("data set " + path + ": cannot create a pipe: " + std::strerror(errno));
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int err = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw Error("data set " + path + ": cannot start the writer: " + std::strerror(err));
  }
  if (pid == 0) {
    ::close(fds[0]);
    forgetStopPolls();
    ::signal(SIGINT, SIG_DFL);  // the parent decides about stops and kills the writer
    ::signal(SIGTERM, SIG_DFL);
    std::string report;
    int code = 0;
    try {
      const DatasetSummary s = writeDatasetFile(sweep, dir, tmp.path);
      report =
          "ok " + std::to_string(s.runs) + " " + std::to_string(s.runs_with_data) + " " + std::to_string(s.samples);
    } catch (const InputError& e) {
      report = std::string("input ") + e.what();
      code = 2;
    } catch (const std::exception& e) {
      report = std::string("error ") + e.what();
      code = 1;
    }
    writeAll(fds[1], report);
    ::close(fds[1]);
    _exit(code);  // no exit handlers: HDF5's would touch a failed file
  }
  ::close(fds[1]);
  std::string report;
  const bool finished = readReport(fds[0], report);
  ::close(fds[0]);
  if (!finished) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  // A stop request, or the writer ended by the signal of one (Ctrl-C and `timeout` signal the whole process group:
  // the writer may die of it before this process has seen its own).
  const int stop_signal =
      WIFSIGNALED(status) && (WTERMSIG(status) == SIGINT || WTERMSIG(status) == SIGTERM) ? WTERMSIG(status) : 0;
  if (!finished || stopRequested() || stop_signal != 0)
    throw sim::Interrupted(SolverError("data set " + path + ": not written (interrupted); nothing was left behind", 0.0,
                                       "INTERRUPTED", "dataset"),
                           sim::SimulationResult{}, stopRequested() != 0 ? stopRequested() : stop_signal);
  if (report.rfind("ok ", 0) == 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    DatasetSummary summary;
    summary.path = path;
    std::sscanf(report.c_str() + 3, "%d %d %ld", &summary.runs, &summary.runs_with_data, &summary.samples);
    io::moveIntoPlace(tmp.path, path);
    tmp.keep = true;
    return summary;
  }
  if (report.rfind("input ", 0) == 0) throw InputError(report.substr(6));
  if (report.rfind("error ", 0) == 0) throw Error("data set " + path + ": " + report.substr(6));
  throw Error("data set " + path + ": the writer ended " +
              (WIFSIGNALED(status) ? "by signal " + std::to_string(WTERMSIG(status))
                                   : "with status " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1)) +
              " (out of memory?); nothing was written");
}

}  // namespace jointsim::report
