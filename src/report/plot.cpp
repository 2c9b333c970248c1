// `jointsim plot`: figures of a run folder or a sweep folder, drawn by gnuplot (pngcairo and svg terminals).
//
// The figures of a run come from its experiment type (experiments/registry.hpp: each type describes its
// figures as data), or every column against time for a type without figures; a sweep folder gets bars of its
// runs and an overlay of their key signal. gnuplot.cpp renders them into one script per folder, drawn by one
// gnuplot process. gnuplot writes every figure to a temporary name; they are renamed into place only when
// gnuplot has exited successfully, and removed otherwise.
#include "jointsim/report/plot.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <tuple>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/registry.hpp"
#include "jointsim/io/csv_reader.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/io/json.hpp"
#include "jointsim/io/output.hpp"
#include "report/gnuplot.hpp"
#include "report/run_folder.hpp"

extern char** environ;

namespace jointsim::report {
namespace {
namespace fs = std::filesystem;
using gp::Figure;
using gp::Key;
using gp::num;
using gp::Panel;
using gp::quote;
using gp::Series;

/// A regular file's bytes (bounded; empty when unreadable, e.g. a FIFO planted as summary.json).
std::string readTextFile(const std::string& path) { return io::readBoundedFile(path); }

/// A run folder with the gnuplot variable holding its CSV path.
struct LoadedRun : RunFolder {
  std::string var;
};

LoadedRun loadRun(const std::string& run_dir) {
  LoadedRun run;
  static_cast<RunFolder&>(run) = loadRunFolder(run_dir);
  return run;
}

/// The figures of a run: its type's (registry), else every column against time.
std::vector<Figure> runFigures(const LoadedRun& run, std::map<std::string, std::string>& blocks) {
  std::vector<experiments::Figure> figs;
  if (const experiments::ExperimentType* t = experiments::findExperimentType(run.data.type); t && t->figures)
    figs = t->figures(run.data);
  if (figs.empty()) figs = experiments::genericFigures(run.data);
  std::vector<Figure> out;
  for (const auto& f : figs) out.push_back(gp::translate(f, run.var, run.data.time(), blocks));
  return out;
}

// ------------------------------------------------------------------------------------------------ sweeps

/// Datablock-safe run name (the datablock is comma-separated).
std::string cellText(std::string s) {
  for (char& c : s)
    if (c == ',' || c == '"' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  return "\"" + s + "\"";
}

struct SweepPlan {
  std::vector<Figure> figures;
  std::vector<LoadedRun> runs;  ///< the runs of the overlay (their `var` set)
  std::map<std::string, std::string> blocks;
};

SweepPlan sweepFigures(const std::string& sweep_dir) {
  SweepPlan plan;
  const std::string name = fs::path(sweep_dir).filename().string();
  const auto rows = readManifest((fs::path(sweep_dir) / "manifest.csv").string());
  // Per-run bars of wall time and real-time factor, coloured by status.
  const std::map<std::string, std::string> colours{{"ok", "0x2ca02c"}, {"failed", "0xd62728"}};
  std::string block;
  std::vector<std::string> statuses;
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto it = colours.find(rows[i].status);
    block += std::to_string(i) + "," + cellText(rows[i].run) + "," + num(rows[i].wall_time_s) + "," +
             num(rows[i].real_time_factor) + "," + (it == colours.end() ? "0x7f7f7f" : it->second) + "\n";
    if (std::find(statuses.begin(), statuses.end(), rows[i].status) == statuses.end())
      statuses.push_back(rows[i].status);
  }
  plan.blocks["$runs"] = block;
  // Horizontal bars (run names on the y axis, first run on top): long fault-run names stay readable.
  Figure bars{"sweep_runs", name + ": runs of the sweep (" + std::to_string(rows.size()) + ")", 1, 2, {}};
  const bool labels = rows.size() <= 60;
  const std::string yrange = "set yrange [" + num(static_cast<double>(rows.size()) - 0.4) + ":-0.6]\n";
  bool first = true;
  for (const auto& [col, quantity, title] : std::vector<std::tuple<int, std::string, std::string>>{
           {3, "wall time [s]", "wall-clock time per run"},
           {4, "real-time factor (sim time / wall time)", "real-time factor per run"}}) {
    double vmax = 0.0;  // at most about four labelled x tics: the first panel is narrow
    for (const auto& r : rows) vmax = std::max(vmax, col == 3 ? r.wall_time_s : r.real_time_factor);
    const std::string xtics = vmax > 0 ? "set xtics " + num(gp::niceCeil(vmax / 4)) + "\n" : std::string();
    Panel p;
    p.title = title;
    p.xlabel = quantity;
    p.ylabel = "";
    p.time_axis = false;
    p.key = Key::bottom_right;
    p.settings =
        "set style fill solid 0.85 border lc rgb '#404040'\nset xrange [0:*]\nset grid xtics noytics\n" + yrange +
        xtics +
        (first && labels ? std::string("set ytics scale 0 font ',9'\n") : std::string("set ytics scale 0 format ''\n"));
    Series s;
    s.data = "$runs";
    s.header = false;
    const std::string c = std::to_string(col);
    s.using_ = "(0.5*$" + c + "):1:(0):" + c + ":($1-0.35):($1+0.35):5" +
               (first && labels ? std::string(":ytic(2)") : std::string());
    s.style = "boxxyerror lc rgb variable";
    p.series.push_back(s);
    for (const auto& st : statuses) {  // legend entries: one per status
      const auto it = colours.find(st);
      Series l;
      l.data = "NaN";
      l.header = false;
      l.using_.clear();
      l.title = "status " + st;
      l.style = "boxes lc rgb '" + std::string("#") + (it == colours.end() ? "7f7f7f" : it->second.substr(2)) + "'";
      p.series.push_back(l);
    }
    bars.panels.push_back(p);
    first = false;
  }
  plan.figures.push_back(bars);

  // Overlay of the key signal across the runs that have a log of the same experiment.
  std::vector<std::pair<std::string, LoadedRun>> runs;
  for (const auto& row : rows) {
    const auto dir = runFolder(sweep_dir, row);
    if (!dir) continue;
    try {
      runs.emplace_back(row.run, loadRun(*dir));
    } catch (const InputError&) {
      // a failed run has no log: it only appears in the bars
    }
  }
  if (runs.empty()) return plan;
  for (const auto& [run_name, r] : runs)
    if (r.data.type != runs.front().second.data.type || r.data.experiment != runs.front().second.data.experiment)
      return plan;
  const auto key = keySignal(runs.front().second.data);
  if (!key) return plan;
  Figure overlay{"sweep_overlay",
                 name + ": " + key->what + " across runs (" + runs.front().second.data.experiment + ")",
                 1,
                 1,
                 {}};
  Panel p;
  p.title = key->what;
  p.xlabel = key->xlabel;
  p.ylabel = key->ylabel;
  p.time_axis = key->x == runs.front().second.data.name(runs.front().second.data.time());
  p.key = Key::outside;
  if (runs.size() > 30) p.key = Key::none;
  for (size_t i = 0; i < runs.size(); ++i) {
    LoadedRun& r = runs[i].second;
    const int x = r.data.col(key->x), y = r.data.col(key->y), ym = key->y_minus.empty() ? -2 : r.data.col(key->y_minus);
    if (x < 0 || y < 0 || ym == -1) continue;
    r.var = "run" + std::to_string(plan.runs.size());
    Series s;
    s.data = r.var;
    s.title = runs[i].first;
    const std::string yexpr = "$" + std::to_string(y + 1) + (ym >= 0 ? "-$" + std::to_string(ym + 1) : std::string());
    s.using_ = std::to_string(x + 1) + ":((" + yexpr + ")*" + num(key->factor) + ")";
    p.series.push_back(s);
    plan.runs.push_back(r);
  }
  if (p.series.empty()) return plan;
  overlay.panels.push_back(p);
  plan.figures.push_back(overlay);
  return plan;
}
/// (or -1 if it could not start, 128 + signal if killed).
int runProcess(const std::string& exe, const std::vector<std::string>& args, const std::string& stderr_path) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> argv_s{exe};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

/// Removes the listed files when it goes out of scope (temporary script, stderr capture, unrenamed figures).
struct Cleanup {
  std::vector<std::string> paths;
  ~Cleanup() {
    for (const auto& p : paths) std::remove(p.c_str());
  }
};

}  // namespace

std::string findGnuplot(const std::string& requested) {
  const std::string name = requested.empty() ? "gnuplot" : requested;
  auto executable = [](const fs::path& p) { return io::isRegularFile(p.string()) && ::access(p.c_str(), X_OK) == 0; };
  if (name.find('/') != std::string::npos) {
    if (executable(name)) return name;
  } else if (const char* path = std::getenv("PATH")) {
    std::stringstream ss(path);
    for (std::string dir; std::getline(ss, dir, ':');) {
      const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
      if (executable(candidate)) return candidate.string();
    }
  }
  throw InputError("gnuplot not found; install gnuplot-nox (scripts/install-deps.sh)" +
                   (requested.empty() ? std::string() : " (looked for '" + requested + "')"));
}

void gp::runScript(const std::string& gnuplot, const std::string& body, const std::vector<std::string>& finals,
                   const std::string& out_dir, const std::string& what) {
  // Run gnuplot on a temporary copy whose outputs carry a temporary suffix; rename them when it succeeded.
  const std::string suffix = ".tmp." + std::to_string(static_cast<long>(::getpid()));
  const std::string script = (fs::path(out_dir) / (".jointsim_plot" + suffix + ".gp")).string();
  const std::string errors = (fs::path(out_dir) / (".jointsim_plot" + suffix + ".err")).string();
  Cleanup cleanup;
  cleanup.paths = {script, errors};
  for (const auto& f : finals) cleanup.paths.push_back(f + suffix);
  io::writeFileAtomically(script, "outsuffix = " + quote(suffix) + "\n" + body);
  const int status = runProcess(gnuplot, {script}, errors);
  if (status != 0) {
    std::string err = readTextFile(errors);
    while (!err.empty() && std::isspace(static_cast<unsigned char>(err.back()))) err.pop_back();
    if (err.size() > 4000) err = "..." + err.substr(err.size() - 4000);
    throw Error("gnuplot (" + gnuplot + ") failed with exit status " + std::to_string(status) + " drawing " + what +
                (err.empty() ? std::string() : ":\n" + err));
  }
  for (const auto& f : finals) {
    if (!io::isRegularFile(f + suffix)) throw Error(f + ": gnuplot did not write this figure");
    if (std::rename((f + suffix).c_str(), f.c_str()) != 0)
      throw Error(f + ": cannot move the figure into place: " + std::strerror(errno));
  }
}

PlotScript plotScript(const std::string& run_dir, const std::string& fig_dir, const PlotOptions& options) {
  if (options.width < 200 || options.height < 150 || options.width > 10000 || options.height > 10000)
    throw InputError("plot size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                     " pixels: expected a width of 200 to 10000 and a height of 150 to 10000");
  const OutputFolder folder = outputFolder(run_dir);
  const fs::path dir = folder.path;
  const bool is_run = folder.is_run;

  // What to draw.
  std::vector<Figure> figures;
  std::vector<LoadedRun> sources;
  std::map<std::string, std::string> blocks;
  PlotScript result;
  if (is_run) {
    LoadedRun run = loadRun(dir.string());
    run.var = "csv";
    figures = runFigures(run, blocks);
    result.name = run.data.experiment;
    sources.push_back(std::move(run));
  } else {
    SweepPlan plan = sweepFigures(dir.string());
    figures = std::move(plan.figures);
    sources = std::move(plan.runs);
    blocks = std::move(plan.blocks);
    result.name = "sweep";
  }

  const fs::path out_dir = fig_dir.empty() ? dir / "figures" : fs::absolute(fig_dir).lexically_normal();
  result.fig_dir = out_dir.string();

  // The script: data paths and blocks, then every figure as PNG (and SVG).
  const double font_scale = std::max(0.7, std::min(options.width / 1400.0, options.height / 900.0));
  const std::string font = "font 'DejaVu Sans," + num(std::round(11 * font_scale)) + "'";
  const std::string size = "size " + std::to_string(options.width) + "," + std::to_string(options.height);
  const std::string png =
      "set terminal pngcairo " + size + " noenhanced " + font + " linewidth 1 background rgb 'white'";
  const std::string svg = "set terminal svg " + size + " noenhanced " + font + " linewidth 1 background rgb 'white'";
  std::ostringstream body;
  body << "# Figures of " << gp::comment(dir.string()) << ", written by `jointsim plot` (docs/plots.md).\n"
       << "# Rerun with: gnuplot THIS_FILE (figures are written to their final names)\n";
  for (const auto& r : sources) body << r.var << " = " << quote(r.csv) << "\n";
  for (const auto& [block_name, text] : blocks) body << block_name << " << EOD\n" << text << "EOD\n";
  body << gp::kLineTypes;
  for (const auto& f : figures) {
    const std::string path = (out_dir / (f.stem + ".png")).string();
    body << gp::renderFigure(f, png, path, font_scale);
    result.figures.push_back(path);
  }
  if (options.svg)
    for (const auto& f : figures) {
      const std::string path = (out_dir / (f.stem + ".svg")).string();
      body << gp::renderFigure(f, svg, path, font_scale);
      result.figures.push_back(path);
    }
  result.body = body.str();
  return result;
}

std::vector<std::string> plotRun(const std::string& run_dir, const std::string& fig_dir, const PlotOptions& options) {
  const std::string gnuplot = findGnuplot(options.gnuplot);
  const PlotScript plan = plotScript(run_dir, fig_dir, options);
  const fs::path out_dir = plan.fig_dir;
  const std::string& dir = run_dir;
  const std::vector<std::string>& finals = plan.figures;
  const std::string& name = plan.name;
  io::createDirectories(out_dir.string());

  gp::runScript(gnuplot, plan.body, finals, out_dir.string(), "the figures of " + dir);
  std::vector<std::string> written = finals;
  if (options.keep_script) {
    const std::string path = (out_dir / (name + "_plots.gp")).string();
    io::writeFileAtomically(path, "outsuffix = ''\n" + plan.body);
    written.push_back(path);
  }
  return written;
}

}  // namespace jointsim::report