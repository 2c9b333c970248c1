#include "report/gnuplot.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace jointsim::report::gp {

std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'')
      out += "''";
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      out += ' ';
    else
      out += c;
  }
  return out + "'";
}

std::string comment(const std::string& s) {
  std::string out = s;
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  return out;
}

std::string num(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", x);
  return buf;
}

namespace {

const char* styleOf(experiments::LineStyle s) {
  using experiments::LineStyle;
  switch (s) {
    case LineStyle::Line: return "lines";
    case LineStyle::Dashed: return "lines dt 2 lw 2";
    case LineStyle::Emphasis: return "lines lw 2.5 lc rgb '#000000'";
    case LineStyle::Steps: return "steps";
    case LineStyle::ThickSteps: return "steps lw 2";
    case LineStyle::Samples: return "points pt 7 ps 0.3 lc rgb '#a0a0a0'";
    case LineStyle::Markers: return "points pt 7 ps 1.6 lc rgb '#d62728'";
  }
  return "lines";
}

}  // namespace

Figure translate(const experiments::Figure& f, const std::string& var, int time_col,
                 std::map<std::string, std::string>& blocks) {
  Figure g{f.stem, f.title, f.rows, f.cols, {}};
  for (const experiments::Panel& p : f.panels) {
    Panel q;
    static_cast<experiments::PanelLayout&>(q) = p;
    if (p.y_step > 0) q.settings += "set ytics " + num(p.y_step) + "\n";
    if (std::isfinite(p.y_min) && std::isfinite(p.y_max))
      q.settings += "set yrange [" + num(p.y_min) + ":" + num(p.y_max) + "]\n";
    for (const experiments::Series& s : p.series) {
      Series t;
      t.title = s.title;
      t.style = styleOf(s.style);
      t.magnitude = s.magnitude;
      t.y2 = s.y2;
      if (!s.points.empty()) {
        const std::string name = "$points" + std::to_string(blocks.size() + 1);
        std::string block;
        for (const auto& pt : s.points) block += num(pt[0]) + "," + num(pt[1]) + "\n";
        blocks[name] = block;
        t.data = name;
        t.header = false;
        t.using_ = "1:2";
      } else {
        t.data = var;
        const std::string x = std::to_string((s.x >= 0 ? s.x : time_col) + 1), y = std::to_string(s.y + 1);
        if (s.y_minus < 0 && s.offset == 0.0 && s.factor == 1.0) {
          t.using_ = x + ":" + y;
        } else {
          std::string inner = "$" + y;
          if (s.y_minus >= 0) inner += "-$" + std::to_string(s.y_minus + 1);
          if (s.offset != 0.0) inner += "-(" + num(s.offset) + ")";
          t.using_ = x + ":" + (s.factor == 1.0 ? "(" + inner + ")" : "((" + inner + ")*" + num(s.factor) + ")");
        }
      }
      q.series.push_back(t);
    }
    g.panels.push_back(q);
  }
  return g;
}

/// Standard look: white background, light grid, colour-blind-friendly line colours (matplotlib's tab10).
const char* const kStyle = "set encoding utf8\n"
                           "set datafile separator comma\n"
                           "set grid lc rgb '#d8d8d8' lw 1 dt 1\n"
                           "set border lw 1.2\n"
                           "set tics out nomirror\n"
                           "set mxtics\n"
                           "set mytics\n"
                           "set format y '%g'\n"
                           "set format x '%g'\n";

const char* const kLineTypes = "set linetype 1 lc rgb '#1f77b4' lw 1.6 pt 7\n"
                               "set linetype 2 lc rgb '#d62728' lw 1.6 pt 7\n"
                               "set linetype 3 lc rgb '#2ca02c' lw 1.6 pt 7\n"
                               "set linetype 4 lc rgb '#ff7f0e' lw 1.6 pt 7\n"
                               "set linetype 5 lc rgb '#9467bd' lw 1.6 pt 7\n"
                               "set linetype 6 lc rgb '#8c564b' lw 1.6 pt 7\n"
                               "set linetype 7 lc rgb '#e377c2' lw 1.6 pt 7\n"
                               "set linetype 8 lc rgb '#7f7f7f' lw 1.6 pt 7\n"
                               "set linetype 9 lc rgb '#bcbd22' lw 1.6 pt 7\n"
                               "set linetype 10 lc rgb '#17becf' lw 1.6 pt 7\n"
                               "set linetype cycle 10\n";

/// The smallest of 1, 2, 5 × 10^n that is at least x > 0.
double niceCeil(double x) {
  const double e = std::pow(10.0, std::floor(std::log10(x)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * e >= x * (1 - 1e-12)) return m * e;
  return 10 * e;
}

/// The `using` specification `x:y` with y divided by k.
std::string scaleY(const std::string& using_, double k) {
  const size_t colon = using_.find(':');
  const std::string x = using_.substr(0, colon), y = using_.substr(colon + 1);
  const bool plain =
      !y.empty() && std::all_of(y.begin(), y.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
  return x + ":((" + (plain ? "$" + y : y) + ")/" + num(k) + ")";
}

/// Moves series an order of magnitude smaller than the largest to a right axis of the same unit (auto_y2).
void resolveAxes(Panel& p) {
  if (p.auto_y2 && p.y2label.empty() && p.series.size() >= 2) {
    double largest = 0;
    for (const auto& s : p.series) largest = std::max(largest, s.magnitude);
    bool moved = false;
    for (auto& s : p.series)
      if (s.magnitude > 0 && s.magnitude < largest / 20) {
        s.y2 = true;
        s.title += " (right axis)";
        moved = true;
      }
    if (moved) p.y2label = p.ylabel + " (right axis)";
  }
  p.auto_y2 = false;
}

bool hasY2(const Panel& p) {
  return std::any_of(p.series.begin(), p.series.end(), [](const Series& s) { return s.y2; });
}

size_t titledSeries(const Panel& p) {
  return static_cast<size_t>(
      std::count_if(p.series.begin(), p.series.end(), [](const Series& s) { return !s.title.empty(); }));
}

Key effectiveKey(const Panel& p) {
  if (p.key != Key::automatic) return p.key;
  return titledSeries(p) > 4 ? Key::outside : Key::top_right;
}

/// Explicit right-axis tics i·step over ±span, labelled with %g of the rounded value (gnuplot's own
/// `start, step` tics accumulate rounding errors: a "0" tic would read -1.38778e-17).
std::string y2Tics(double step, double span) {
  const int n = static_cast<int>(std::min(200.0, std::ceil(span / step)));
  std::string out = "(";
  for (int i = -n; i <= n; ++i) {
    char text[40];
    std::snprintf(text, sizeof text, "%.6g", i * step);
    out += (i > -n ? ", " : "") + quote(text) + " " + num(i * step);
  }
  return out + ")";
}

/// gnuplot commands drawing one panel (its axes already resolved).
/// `key_at`: screen x of the legend of a stacked panel with an outside legend (left of the reserved column).
std::string renderPanel(const Panel& p, double key_at = 0) {
  // The right axis is linked to the left one, y2 = k·y with k a round number, so that both share zero and
  // the grid; right-axis series are drawn on the left axis divided by k (so autoscaling sees every series).
  double mag1 = 0, mag2 = 0;
  for (const auto& s : p.series) (s.y2 ? mag2 : mag1) = std::max(s.y2 ? mag2 : mag1, s.magnitude);
  const bool y2 = hasY2(p);
  const double k = (mag1 > 0 && mag2 > 0) ? niceCeil(mag2 / mag1) : 1.0;
  std::ostringstream o;
  o << "set title " << quote(p.title) << "\n";
  o << "set xlabel " << quote(p.xlabel) << "\n";
  o << "set ylabel " << quote(p.ylabel) << "\n";
  if (y2)
    o << "set y2label " << quote(p.y2label) << "\nset link y2 via y*" << num(k) << " inverse y/" << num(k)
      << "\nset y2tics "
      << y2Tics(p.y2_step > 0 ? p.y2_step : niceCeil(k * (mag1 > 0 ? mag1 : 1) / 5), 1.6 * std::max(k * mag1, mag2))
      << "\nunset my2tics\n";
  else
    o << "unset y2label\nunset link y2\nunset y2tics\nunset my2tics\n";
  o << (p.time_axis ? "set autoscale xfix\n" : "set autoscale x\n");
  const size_t titled = titledSeries(p);
  const Key key = effectiveKey(p);
  switch (key) {
    case Key::none: o << "unset key\n"; break;
    case Key::outside:
      if (key_at > 0)
        o << "set key at screen " << num(key_at) << ", graph 1 left top";
      else
        o << "set key outside right top";
      o << " vertical Left reverse noopaque nobox samplen 2\n";
      break;
    case Key::top_left: o << "set key inside top left Left reverse opaque box lc rgb '#b0b0b0' samplen 2\n"; break;
    case Key::bottom_right:
      o << "set key inside bottom right Left reverse opaque box lc rgb '#b0b0b0' samplen 2\n";
      break;
    default: o << "set key inside top right Left reverse opaque box lc rgb '#b0b0b0' samplen 2\n"; break;
  }
  // Headroom for a legend inside the plot, so it does not hide the curves' peaks.
  if (key == Key::top_left || key == Key::top_right)
    o << "set offsets 0, 0, graph " << num(0.1 * static_cast<double>(titled) + 0.04) << ", graph 0.03\n";
  else
    o << "set offsets 0, 0, graph 0.03, graph 0.03\n";
  o << p.settings;
  o << "plot ";
  for (size_t i = 0; i < p.series.size(); ++i) {
    const Series& s = p.series[i];
    o << (i ? ", \\\n     " : "") << s.data;
    if (s.header) o << " skip 1";
    if (!s.using_.empty()) o << " using " << (s.y2 ? scaleY(s.using_, k) : s.using_);
    o << " with " << s.style << (s.title.empty() ? std::string(" notitle") : " title " + quote(s.title));
  }
  o << "\n";
  // Reset what a panel may have changed for the next one.
  o << "set xtics norotate\nset autoscale y\nset autoscale y2\nset ytics autofreq\nset grid xtics ytics\n"
       "set style fill empty\n";
  return o.str();
}

std::string renderFigure(const Figure& f, const std::string& terminal, const std::string& output, double font_scale) {
  std::ostringstream o;
  o << "\n# ---- " << f.stem << "\n" << terminal << "\n";
  o << "set output " << quote(output) << ".outsuffix\n";
  o << "reset\n" << kStyle;
  std::vector<Panel> panels = f.panels;
  for (auto& p : panels) resolveAxes(p);
  o << "set multiplot layout " << f.rows << "," << f.cols << " title " << quote(f.title) << " font ',"
    << num(std::round(14 * font_scale)) << "'";
  double key_at = 0;
  if (f.cols == 1) {
    // Stacked time panels: equal margins so that their time axes line up; room on the right for legends
    // outside the plot and for a right axis.
    const bool outside =
        std::any_of(panels.begin(), panels.end(), [](const Panel& p) { return effectiveKey(p) == Key::outside; });
    const bool y2 = std::any_of(panels.begin(), panels.end(), hasY2);
    // Width of an outside legend: the longest entry (≈ 8 px per character at the 1400 px reference size,
    // plus the sample line), at least 16 % of the figure, at most 40 %.
    size_t longest = 0;
    for (const auto& p : panels)
      if (effectiveKey(p) == Key::outside)
        for (const auto& sr : p.series) longest = std::max(longest, sr.title.size());
    const double key_width = std::clamp((8.0 * static_cast<double>(longest) + 60.0) / 1400.0, 0.16, 0.40);
    const double right = 1 - (outside ? key_width : 0.02) - (y2 ? 0.06 : 0.0);
    if (outside) key_at = right + (y2 ? 0.07 : 0.01);
    o << " margins 0.08, " << num(right) << ", " << num(f.rows > 1 ? 0.07 : 0.09) << ", 0.91 spacing 0.1, 0.13";
  }
  o << "\n";
  for (const auto& p : panels) o << renderPanel(p, key_at);
  o << "unset multiplot\nset output\n";
  return o.str();
}

/// Runs `exe args...` with stdin and stdout on /dev/null and stderr into `stderr_path`; returns the exit status

}  // namespace jointsim::report::gp
