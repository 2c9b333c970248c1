#pragma once
// Internal: the gnuplot renderer of `jointsim plot`. Figures described by the experiment types
// (experiments/figures.hpp) are translated into gnuplot panels (`using` clauses on the run's CSV or on inline
// datablocks) and rendered into one script; every string that comes from a file goes through quote().
#include <map>
#include <string>
#include <vector>

#include "jointsim/experiments/figures.hpp"

namespace jointsim::report::gp {

using experiments::Key;

struct Series {
  std::string data;             ///< gnuplot expression naming the data: a path variable or a datablock ($name)
  std::string using_;           ///< the `using` specification
  std::string title;            ///< legend entry (empty: none)
  std::string style = "lines";  ///< what follows `with`
  double magnitude = 0;         ///< max |y|, for the automatic right axis (0: stays on the left)
  bool header = true;           ///< the data start with a header line to skip
  bool y2 = false;              ///< on the right axis
};

struct Panel : experiments::PanelLayout {
  std::vector<Series> series;
  std::string settings;  ///< extra gnuplot commands for this panel (built here, never from input text)
};

struct Figure {
  std::string stem;   ///< file name without extension
  std::string title;  ///< figure title (starts with the experiment name)
  int rows = 1, cols = 1;
  std::vector<Panel> panels;
};

/// gnuplot single-quoted string literal: '' for ', and every control character (newline included) as a blank,
/// so no text from a file can end the string or the command.
std::string quote(const std::string& s);
/// Text for a `#` comment line: every control character as a blank, so the comment cannot end early.
std::string comment(const std::string& s);
/// A number for a script (%.10g).
std::string num(double x);
/// The smallest of 1, 2, 5 × 10^n that is at least x > 0.
double niceCeil(double x);
/// A figure of a run whose CSV is the gnuplot variable `var` (its time column `time_col`); inline points become
/// datablocks added to `blocks`.
Figure translate(const experiments::Figure& f, const std::string& var, int time_col,
                 std::map<std::string, std::string>& blocks);
/// The script lines drawing one figure into `output` (+ the suffix variable outsuffix) with `terminal`.
std::string renderFigure(const Figure& f, const std::string& terminal, const std::string& output, double font_scale);
/// Runs gnuplot on `body` (a script whose figures are written to their final paths + the variable outsuffix) in
/// `out_dir`: the figures `finals` appear, renamed into place, only when gnuplot succeeded; Error quoting gnuplot's
/// stderr otherwise (`what` names what was drawn). The temporary script and outputs are removed in any case.
void runScript(const std::string& gnuplot, const std::string& body, const std::vector<std::string>& finals,
               const std::string& out_dir, const std::string& what);
/// Line colours (matplotlib's tab10) for the top of a script.
extern const char* const kLineTypes;

}  // namespace jointsim::report::gp
