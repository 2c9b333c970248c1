// Reading run and sweep folders (run_folder.hpp).
#include "report/run_folder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/registry.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/io/json.hpp"

namespace jointsim::report {
namespace fs = std::filesystem;

OutputFolder outputFolder(const std::string& dir) {
  if (!io::isDirectory(dir)) throw InputError(dir + ": no such run folder");
  const fs::path abs = fs::absolute(dir).lexically_normal();
  OutputFolder out;
  out.path = abs.string();
  out.is_run = io::isRegularFile((abs / "summary.json").string());
  if (!out.is_run && !io::isRegularFile((abs / "manifest.csv").string()))
    throw InputError(dir + ": neither a run folder (summary.json and the CSV log of `jointsim run`) nor a sweep "
                           "folder (manifest.csv of `jointsim batch`)");
  return out;
}

RunFolder loadRunFolder(const std::string& run_dir) {
  RunFolder run;
  run.dir = fs::absolute(run_dir).lexically_normal().string();
  const std::string summary_path = (fs::path(run.dir) / "summary.json").string();
  auto summary =
      std::make_shared<nlohmann::ordered_json>(io::parseJson(io::readBoundedFile(summary_path), summary_path));
  if (summary->is_discarded() || !summary->is_object())
    throw InputError(summary_path + ": not a summary.json of `jointsim run` (a JSON object)");
  experiments::RunData& d = run.data;
  d.summary = summary;
  d.experiment = d.param({"experiment"});
  d.type = d.param({"type"});
  d.status = d.param({"status"});
  // The log: DIR/<experiment>.csv; else the file named by "csv" (the folder may have been moved).
  std::vector<fs::path> candidates;
  if (!d.experiment.empty()) candidates.push_back(fs::path(run.dir) / (d.experiment + ".csv"));
  if (const std::string csv = d.param({"csv"}); !csv.empty()) {
    candidates.push_back(fs::path(run.dir) / fs::path(csv).filename());
    candidates.push_back(fs::path(csv));
  }
  for (const auto& c : candidates)
    if (io::isRegularFile(c.string())) {
      run.csv = fs::absolute(c).lexically_normal().string();
      break;
    }
  if (run.csv.empty()) {
    const std::string why = d.status == "failed" ? " (the run failed: " + d.param({"reason"}) + ")" : "";
    throw InputError(summary_path + ": no CSV log to plot" + why + "; expected " +
                     (candidates.empty() ? std::string("<experiment>.csv") : candidates.front().string()));
  }
  if (d.experiment.empty()) d.experiment = fs::path(run.csv).stem().string();
  // The name becomes the stem of every figure file and part of gnuplot titles: a hand-edited summary must not
  // steer outputs elsewhere.
  if (!isSafeName(d.experiment))
    throw InputError(summary_path +
                     ": experiment: expected a name of letters, digits, '.', '-', '_' (it names the "
                     "figure files), got '" +
                     printable(d.experiment, 80) + "'");
  const io::CsvTable table = io::readCsv(run.csv, false);
  d.data = table.data;
  for (const auto& h : table.header) {
    auto [n, unit] = splitColumn(h);
    d.names.push_back(n);
    d.units.push_back(unit);
  }
  return run;
}

std::vector<ManifestRow> readManifest(const std::string& path) {
  const io::CsvText t = io::readCsvText(path);
  // The first seven columns as written by `jointsim batch` since its first version; later ones (version,
  // commit, start time, inputs) are not needed here.
  const std::vector<std::string> expected{"run",        "status",   "wall_time_s", "sim_time_s", "real_time_factor",
                                          "output_dir", "overrides"};
  if (t.header.size() < expected.size() || !std::equal(expected.begin(), expected.end(), t.header.begin()))
    throw InputError(path + ":1: expected a manifest header starting run,status,wall_time_s,sim_time_s,"
                            "real_time_factor,output_dir,overrides");
  auto number = [](const std::string& s) {
    char* end = nullptr;
    const double x = std::strtod(s.c_str(), &end);
    return (s.empty() || *end != '\0') ? NAN : x;
  };
  std::vector<ManifestRow> rows;
  for (size_t k = 0; k < t.rows.size(); ++k) {
    const auto& cells = t.rows[k];
    if (!isSafeName(cells[0]))
      throw InputError(path + ":" + std::to_string(t.lines[k]) +
                       ": run: expected a run name of letters, digits, '.', '-', "
                       "'_', got '" +
                       printable(cells[0], 80) + "'");
    ManifestRow r;
    r.run = cells[0];
    r.status = cells[1];
    r.wall_time_s = number(cells[2]);
    r.sim_time_s = number(cells[3]);
    r.real_time_factor = number(cells[4]);
    r.output_dir = cells[5];
    r.overrides = cells[6];
    for (size_t c = expected.size(); c < t.header.size() && c < cells.size(); ++c)
      if (!cells[c].empty()) r.extra.emplace_back(t.header[c], cells[c]);
    rows.push_back(r);
  }
  if (rows.empty()) throw InputError(path + ": no runs listed");
  return rows;
}

/// The run folder of a manifest row: output_dir as written (absolute, or relative to the working directory),
/// else relative to the sweep folder, else SWEEP_DIR/<its last component> or SWEEP_DIR/<run>.
std::optional<std::string> runFolder(const std::string& sweep_dir, const ManifestRow& row) {
  std::vector<fs::path> candidates;
  if (!row.output_dir.empty()) {
    const fs::path p(row.output_dir);
    candidates.push_back(p);
    if (p.is_relative()) candidates.push_back(fs::path(sweep_dir) / p);
    candidates.push_back(fs::path(sweep_dir) / p.filename());
  }
  candidates.push_back(fs::path(sweep_dir) / row.run);
  for (const auto& c : candidates)
    if (io::isRegularFile((c / "summary.json").string())) return c.string();
  return std::nullopt;
}

/// The signal of a run overlaid across a sweep: its type's key signal (registry), else its first column.
std::optional<experiments::KeySignal> keySignal(const experiments::RunData& run) {
  if (const experiments::ExperimentType* t = experiments::findExperimentType(run.type); t && t->key_signal)
    if (auto k = t->key_signal(run)) return k;
  if (auto c = run.where([](const std::string&) { return true; }); !c.empty())
    return experiments::timeKeySignal(run, c[0], run.name(c[0]));
  return std::nullopt;
}

}  // namespace jointsim::report
