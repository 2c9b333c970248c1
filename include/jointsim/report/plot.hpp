#pragma once
/// \file
/// Figures of a run folder (`jointsim plot`): reads DIR/summary.json and DIR/<name>.csv written by
/// `jointsim run` (or DIR/manifest.csv written by `jointsim batch`), takes the figures of the experiment
/// type from the registry (experiments/registry.hpp), writes a gnuplot script and runs gnuplot (Debian package gnuplot-nox: pngcairo and svg
/// terminals). Every figure is written to a temporary name and renamed into place once gnuplot has
/// succeeded, so no half-written figure is ever left. The figures of each type are listed in docs/plots.md.

#include <string>
#include <vector>

namespace jointsim::report {

struct PlotOptions {
  bool svg = false;  ///< also write an SVG of every figure (same name, .svg)
  int width = 1400;  ///< size of every PNG [pixels] (an SVG gets the same size in points)
  int height = 900;
  std::string gnuplot;       ///< gnuplot executable (a path or a name looked up on PATH); empty = "gnuplot"
  bool keep_script = false;  ///< also write FIG_DIR/<name>_plots.gp, a standalone script to tweak the figures
};

/// The gnuplot script of a run or sweep folder, built without running gnuplot or writing anything.
struct PlotScript {
  std::string name;                  ///< experiment name (run folder) or "sweep"
  std::string fig_dir;               ///< absolute folder the figures go to
  std::vector<std::string> figures;  ///< final paths of the figures, in the order drawn
  /// Script text: data paths, datablocks and one block per figure. Every figure is written to its final
  /// path followed by the value of the gnuplot variable `outsuffix`, which the caller defines first.
  std::string body;
};

/// Reads the run folder `run_dir` as plotRun does and returns its script; throws as plotRun does for the
/// folder and its files (not for gnuplot, which it does not need).
PlotScript plotScript(const std::string& run_dir, const std::string& fig_dir = {}, const PlotOptions& options = {});

/// Writes the figures of the run folder `run_dir` (a `jointsim run` output with summary.json and the CSV
/// log, or a sweep folder with manifest.csv) into `fig_dir` (created; empty = run_dir/figures) and
/// returns the paths written (PNGs, then SVGs, then the script if requested), in a stable order.
/// Throws InputError (CLI exit 2) for a missing folder, a folder that is neither a run nor a sweep, a run
/// without a CSV (e.g. a failed run), an unreadable CSV or manifest, a bad size, or gnuplot not found;
/// throws Error when gnuplot fails (the message quotes gnuplot's stderr) or a figure cannot be written.
std::vector<std::string> plotRun(const std::string& run_dir, const std::string& fig_dir = {},
                                 const PlotOptions& options = {});

/// The gnuplot executable: `requested` (empty = "gnuplot") as a path if it contains a '/', else searched
/// on PATH. Throws InputError "gnuplot not found; install gnuplot-nox (scripts/install-deps.sh)".
std::string findGnuplot(const std::string& requested = {});

}  // namespace jointsim::report
