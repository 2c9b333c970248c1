#include "jointsim/experiments/figures.hpp"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

namespace jointsim::experiments {

// ------------------------------------------------------------------------------------------------ RunData

int RunData::col(const std::string& n) const {
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == n) return static_cast<int>(i);
  return -1;
}

int RunData::time() const { return std::max(col("time"), 0); }

std::vector<int> RunData::where(const std::function<bool(const std::string&)>& pred) const {
  std::vector<int> out;
  for (size_t i = 0; i < names.size(); ++i)
    if (static_cast<int>(i) != time() && pred(names[i])) out.push_back(static_cast<int>(i));
  return out;
}

double RunData::maxAbs(int c) const { return data.rows() ? data.col(c).cwiseAbs().maxCoeff() : 0.0; }

double RunData::span(int c) const { return data.rows() ? data.col(c).maxCoeff() - data.col(c).minCoeff() : 0.0; }

std::string RunData::param(const std::vector<std::string>& path) const {
  if (!summary) return {};
  const nlohmann::ordered_json* node = summary.get();
  for (const auto& key : path) {
    if (!node->is_object()) return {};
    const auto it = node->find(key);
    if (it == node->end()) return {};
    node = &*it;
  }
  if (node->is_string()) return node->get<std::string>();
  if (node->is_boolean()) return node->get<bool>() ? "true" : "false";
  if (node->is_number()) return node->dump();
  return {};
}

// ------------------------------------------------------------------------------------------------ helpers

bool startsWith(const std::string& s, const std::string& prefix) { return s.compare(0, prefix.size(), prefix) == 0; }

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string stripPrefix(const std::string& s, const std::string& prefix) {
  return startsWith(s, prefix) ? s.substr(prefix.size()) : s;
}

std::string axisLabel(const std::string& quantity, const std::string& unit) {
  return (unit.empty() || unit == "-" || unit == "1") ? quantity : quantity + " [" + unit + "]";
}

void grid(Figure& f, size_t n, size_t max_cols) {
  f.cols = static_cast<int>(std::min(std::max<size_t>(n, 1), max_cols));
  f.rows = static_cast<int>((std::max<size_t>(n, 1) + static_cast<size_t>(f.cols) - 1) / static_cast<size_t>(f.cols));
}

Scaled readableUnit(const std::string& unit, double max_abs) {
  if ((unit == "m" || unit == "rad") && max_abs > 0) {
    if (max_abs < 5e-5) return {1e6, "µ" + unit};
    if (max_abs < 5e-2) return {1e3, "m" + unit};
  }
  return {1, unit};
}

Series timeSeries(const RunData& run, int c, const std::string& title, double factor, LineStyle style) {
  Series s;
  s.y = c;
  s.factor = factor;
  s.title = title;
  s.style = style;
  s.magnitude = run.maxAbs(c) * std::abs(factor);
  return s;
}

Series xySeries(const RunData& run, int x, int c, const std::string& title, LineStyle style) {
  Series s;
  s.x = x;
  s.y = c;
  s.title = title;
  s.style = style;
  s.magnitude = run.maxAbs(c);
  return s;
}

Panel timePanel(const RunData& run, const std::vector<int>& cols, const std::string& title, const std::string& quantity,
                const std::function<std::string(const std::string&)>& legend) {
  Panel p;
  p.title = title;
  p.xlabel = axisLabel("time", run.unit(run.time()));
  p.ylabel = cols.empty() ? quantity : axisLabel(quantity, run.unit(cols.front()));
  for (int c : cols) {
    const std::string& n = run.name(c);
    p.series.push_back(timeSeries(run, c, legend ? legend(n) : n));
  }
  return p;
}

std::vector<std::string> jointsWithPrefix(const RunData& run, const std::string& prefix) {
  std::vector<std::string> joints;
  for (int c : run.where([&](const std::string& n) { return startsWith(n, prefix); }))
    joints.push_back(run.name(c).substr(prefix.size()));
  return joints;
}

std::vector<Figure> genericFigures(const RunData& run) {
  std::vector<Figure> figs;
  const auto cols = run.where([](const std::string&) { return true; });
  const size_t per_page = 6, pages = (cols.size() + per_page - 1) / per_page;
  for (size_t page = 0; page < pages; ++page) {
    Figure f{run.experiment + "_columns_" + std::to_string(page + 1),
             run.experiment + ": all columns (" + std::to_string(page + 1) + "/" + std::to_string(pages) + ")",
             1,
             1,
             {}};
    for (size_t k = page * per_page; k < std::min(cols.size(), (page + 1) * per_page); ++k) {
      const int c = cols[k];
      f.panels.push_back(timePanel(run, {c}, run.name(c), run.name(c)));
      f.panels.back().key = Key::none;
    }
    grid(f, f.panels.size());
    figs.push_back(f);
  }
  return figs;
}

std::optional<KeySignal> timeKeySignal(const RunData& run, int c, const std::string& what) {
  if (c < 0) return std::nullopt;
  KeySignal k;
  k.x = run.name(run.time());
  k.y = run.name(c);
  k.xlabel = axisLabel("time", run.unit(run.time()));
  k.ylabel = axisLabel(k.y, run.unit(c));
  k.what = what;
  return k;
}

}  // namespace jointsim::experiments
