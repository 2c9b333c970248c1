// `jointsim view`: one self-contained HTML page of a run or sweep folder (report/view.hpp, docs/view.md).
//
// The page is the template report/web/viewer.html with the browser libraries, the page script and style, and the
// data (JSON) put in. Everything data-derived travels inside the JSON, whose '<', '>' and '&' are escaped, so no
// byte of a run folder can close the script element or become markup; the page script writes text only through
// textContent.
#include "jointsim/report/view.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <string_view>

#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/experiments/experiment.hpp"
#include "jointsim/experiments/registry.hpp"
#include "jointsim/io/input_files.hpp"
#include "jointsim/io/output.hpp"
#include "jointsim/multibody/algorithms.hpp"
#include "jointsim/multibody/data.hpp"
#include "report/run_folder.hpp"

namespace jointsim::report {
namespace assets {
extern const std::string_view kThreeJs, kOrbitControlsJs, kUplotJs, kUplotCss, kViewerJs, kViewerCss, kViewerHtml;
extern const std::string_view kStlLoaderJs, kObjLoaderJs, kTgaLoaderJs, kColladaLoaderJs;
}  // namespace assets

namespace {
namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using experiments::RunData;

/// A number for the page: finite values as they are, anything else null (JSON has no NaN or infinity).
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

/// A value for the page rounded to `digits` significant digits (so that it is written short), null when not finite.
/// Plotted values keep 8 (the readout shows 6), joint angles 12 (1e-12 rad: the drawn pose is exact to far below a
/// micrometre); times keep every digit (number()).
json rounded(double v, int digits) {
  if (!std::isfinite(v)) return nullptr;
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  const double r = std::strtod(buf, nullptr);
  return std::isfinite(r) ? json(r) : json(v);
}
json plotted(double v) { return rounded(v, 8); }

/// Rows kept when `n` rows are drawn in `slices` columns: per slice the rows of the minimum and maximum of `y`
/// (non-finite values are kept as gaps), in row order; every row when n ≤ 2·slices.
std::vector<Eigen::Index> peakRows(const Eigen::VectorXd& y, int slices) {
  const Eigen::Index n = y.size();
  std::vector<Eigen::Index> rows;
  if (n <= 2 * static_cast<Eigen::Index>(slices)) {
    for (Eigen::Index i = 0; i < n; ++i) rows.push_back(i);
    return rows;
  }
  for (int s = 0; s < slices; ++s) {
    const Eigen::Index a = n * s / slices, b = n * (s + 1) / slices;
    Eigen::Index lo = -1, hi = -1, gap = -1;
    for (Eigen::Index i = a; i < b; ++i) {
      if (!std::isfinite(y[i])) {
        if (gap < 0) gap = i;
        continue;
      }
      if (lo < 0 || y[i] < y[lo]) lo = i;
      if (hi < 0 || y[i] > y[hi]) hi = i;
    }
    for (Eigen::Index i : {lo, hi, gap})
      if (i >= 0) rows.push_back(i);
  }
  rows.push_back(0);  // the ends, so that the plot spans the whole run
  rows.push_back(n - 1);
  std::sort(rows.begin(), rows.end());
  rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  return rows;
}

/// "[unit]" at the end of an axis label, or "".
std::string labelUnit(const std::string& label) {
  const auto open = label.rfind('['), close = label.rfind(']');
  if (open == std::string::npos || close == std::string::npos || close < open) return {};
  return label.substr(open + 1, close - open - 1);
}

/// One figure of the registry as the page draws it: every series as its own decimated x/y arrays, with the log
/// columns and the transform it was computed from (y = ((y_col − y_minus_col) − offset) · factor), so that a reader
/// can recompute any drawn point from the CSV.
json figureJson(const experiments::Figure& f, const RunData& run, int slices) {
  json jf;
  jf["title"] = f.title;
  jf["stem"] = f.stem;
  jf["panels"] = json::array();
  for (const experiments::Panel& p : f.panels) {
    json jp;
    jp["title"] = p.title;
    jp["xlabel"] = p.xlabel;
    jp["ylabel"] = p.ylabel;
    jp["y2label"] = p.y2label;
    jp["time_axis"] = p.time_axis;
    jp["series"] = json::array();
    for (const experiments::Series& s : p.series) {
      json js;
      js["title"] = s.title;
      js["style"] = static_cast<int>(s.style);
      js["y2"] = s.y2;
      Eigen::VectorXd x, y;
      if (!s.points.empty()) {
        x.resize(static_cast<Eigen::Index>(s.points.size()));
        y.resize(x.size());
        for (size_t i = 0; i < s.points.size(); ++i) {
          x[static_cast<Eigen::Index>(i)] = s.points[i][0];
          y[static_cast<Eigen::Index>(i)] = s.points[i][1];
        }
        js["unit"] = labelUnit(s.y2 ? p.y2label : p.ylabel);
      } else {
        if (s.y < 0 || s.y >= run.data.cols() || s.x >= run.data.cols() || s.y_minus >= run.data.cols()) continue;
        const int xc = s.x < 0 ? run.time() : s.x;
        x = run.data.col(xc);
        y = run.data.col(s.y);
        if (s.y_minus >= 0) y -= run.data.col(s.y_minus);
        y = ((y.array() - s.offset) * s.factor).matrix();
        js["x_col"] = run.name(xc);
        js["y_col"] = run.name(s.y);
        if (s.y_minus >= 0) js["y_minus_col"] = run.name(s.y_minus);
        js["factor"] = s.factor;
        js["offset"] = s.offset;
        const bool same_unit = s.factor == 1.0 && (s.y_minus < 0 || run.unit(s.y_minus) == run.unit(s.y));
        js["unit"] = same_unit ? run.unit(s.y) : labelUnit(s.y2 ? p.y2label : p.ylabel);
      }
      std::vector<Eigen::Index> keep;
      if (p.time_axis && s.points.empty()) {
        keep = peakRows(y, slices);
      } else {  // a curve in the plane (hysteresis, friction map): evenly strided rows
        const Eigen::Index n = y.size(), stride = std::max<Eigen::Index>(1, (n + 2 * slices - 1) / (2 * slices));
        for (Eigen::Index i = 0; i < n; i += stride) keep.push_back(i);
        if (n > 0 && keep.back() != n - 1) keep.push_back(n - 1);
      }
      // Against time: the rows of the log (compactTimes() turns them into indices of the run's time array).
      const bool timed = p.time_axis && s.points.empty() && (s.x < 0 || s.x == run.time());
      json jx = json::array(), jy = json::array();
      for (Eigen::Index i : keep) {
        jx.push_back(timed ? json(i) : plotted(x[i]));
        jy.push_back(plotted(y[i]));
      }
      js[timed ? "rows" : "x"] = std::move(jx);
      js["y"] = std::move(jy);
      jp["series"].push_back(std::move(js));
    }
    jf["panels"].push_back(std::move(jp));
  }
  return jf;
}

std::vector<experiments::Figure> figuresOf(const RunData& run) {
  std::vector<experiments::Figure> figs;
  if (const experiments::ExperimentType* t = experiments::findExperimentType(run.type); t && t->figures)
    figs = t->figures(run);
  if (figs.empty()) figs = experiments::genericFigures(run);
  return figs;
}

/// The document with every whole-number value written as an integer: the summary keeps YAML numbers as doubles,
/// and keys that take a count (e.g. solver.max_order) refuse "2.0" while every real-valued key reads "2".
void wholeNumbersAsIntegers(json& j) {
  if (j.is_object() || j.is_array()) {
    for (auto& v : j) wholeNumbersAsIntegers(v);
  } else if (j.is_number_float()) {
    const double v = j.get<double>();
    if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 9.0e15) j = static_cast<std::int64_t>(v);
  }
}

/// The figure that characterises a run of its type: the first whose panels are all curves in the plane (the
/// clamping curves of a clamping run, the friction map of a rig); -1 when every figure is against time.
int primaryFigure(const std::vector<experiments::Figure>& figs) {
  for (size_t k = 0; k < figs.size(); ++k) {
    const auto& panels = figs[k].panels;
    if (!panels.empty() &&
        std::none_of(panels.begin(), panels.end(), [](const experiments::Panel& p) { return p.time_axis; }))
      return static_cast<int>(k);
  }
  return -1;
}

/// The experiment of a run, rebuilt from its summary's document (parameters.config) as the file it came from;
/// null with `why` set when that is not possible.
std::shared_ptr<experiments::Experiment> rebuildExperiment(const RunData& run, std::string& why) {
  if (!run.summary) {
    why = "the summary has no experiment document";
    return nullptr;
  }
  const json& s = *run.summary;
  const json* config = nullptr;
  if (auto p = s.find("parameters"); p != s.end() && p->is_object())
    if (auto c = p->find("config"); c != p->end() && c->is_object()) config = &*c;
  if (!config) {
    why = "the summary has no parameters.config (the experiment document)";
    return nullptr;
  }
  std::string path;
  if (auto in = s.find("inputs"); in != s.end() && in->is_array() && !in->empty() && (*in)[0].is_object())
    if (auto p = (*in)[0].find("path"); p != (*in)[0].end() && p->is_string()) path = p->get<std::string>();
  if (path.empty()) path = run.param({"parameters", "config_file"});
  if (path.empty()) path = "summary.json";
  try {
    json doc = *config;
    wholeNumbersAsIntegers(doc);
    return experiments::loadExperimentText(doc.dump(), path);
  } catch (const std::exception& e) {
    why = std::string("the experiment could not be rebuilt from the summary: ") + e.what();
    return nullptr;
  }
}

/// Input files whose content changed since the run (their recorded hash no longer matches). Each file is hashed
/// once per page (`hashes`: path → hash, shared by the runs of a sweep), at most 256 different files in all.
json changedInputs(const RunData& run, std::map<std::string, std::string>& hashes) {
  json out = json::array();
  if (!run.summary) return out;
  auto in = run.summary->find("inputs");
  if (in == run.summary->end() || !in->is_array()) return out;
  for (const json& f : *in) {
    if (!f.is_object() || !f.contains("path") || !f.contains("hash") || !f["path"].is_string() ||
        !f["hash"].is_string())
      continue;
    const std::string path = f["path"].get<std::string>();
    auto it = hashes.find(path);
    if (it == hashes.end()) {
      if (hashes.size() >= 256) continue;
      it = hashes.emplace(path, io::fileHash(path)).first;
    }
    if (it->second != f["hash"].get<std::string>()) out.push_back(path);
  }
  return out;
}

json placementJson(const multibody::Placement& X) {
  json j;
  j["p"] = {X.p.x(), X.p.y(), X.p.z()};
  json r = json::array();
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) r.push_back(X.R(i, k));
  j["R"] = std::move(r);  // row-major
  return j;
}

std::string base64(const std::string& bytes) {
  static const char* const kDigits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += {kDigits[(v >> 18) & 63], kDigits[(v >> 12) & 63], kDigits[(v >> 6) & 63], kDigits[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    out += {kDigits[(v >> 18) & 63], kDigits[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8);
    out += {kDigits[(v >> 18) & 63], kDigits[(v >> 12) & 63], kDigits[(v >> 6) & 63], '='};
  }
  return out;
}

/// The mesh format of a file name by its extension ("stl", "obj", "dae"), "" for others.
std::string meshFormat(const std::string& name) {
  const auto dot = name.rfind('.');
  if (dot == std::string::npos) return {};
  std::string ext = name.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == "stl" || ext == "obj" || ext == "dae" ? ext : std::string();
}

/// The link geometry of the robot file (URDF <visual>): primitives, and meshes embedded (base64) up to
/// `budget` bytes in all; a mesh not found, of another format or over the budget is listed in `notes`.
json visualsJson(const multibody::Model& m, long budget, std::vector<std::string>& formats, json& notes) {
  json out = json::array();
  long used = 0;
  for (const multibody::Visual& v : m.visuals) {
    json j;
    j["link"] = v.link;
    j["joint"] = v.joint;
    j["origin"] = placementJson(v.placement);
    j["size"] = {v.size.x(), v.size.y(), v.size.z()};
    if (v.rgba.minCoeff() >= 0) j["rgba"] = {v.rgba[0], v.rgba[1], v.rgba[2], v.rgba[3]};
    switch (v.shape) {
      case multibody::Visual::Shape::Box: j["shape"] = "box"; break;
      case multibody::Visual::Shape::Cylinder: j["shape"] = "cylinder"; break;
      case multibody::Visual::Shape::Sphere: j["shape"] = "sphere"; break;
      case multibody::Visual::Shape::Mesh: {
        j["shape"] = "mesh";
        j["mesh"] = v.mesh;
        const std::string format = meshFormat(v.mesh);
        std::string why;
        std::string bytes;
        if (format.empty())
          why = "not an STL, OBJ or COLLADA (.dae) file";
        else if (v.mesh_path.empty())
          why = "file not found";
        else if ((bytes = io::readBoundedFile(v.mesh_path)).empty())
          why = "cannot be read";
        else if (used + static_cast<long>(bytes.size()) > budget)
          why = "over the page's mesh budget";
        if (!why.empty()) {
          notes.push_back("mesh " + v.mesh + " of link " + v.link + " not drawn: " + why);
          continue;
        }
        used += static_cast<long>(bytes.size());
        j["format"] = format;
        j["data"] = base64(bytes);
        if (std::find(formats.begin(), formats.end(), format) == formats.end()) formats.push_back(format);
        break;
      }
    }
    out.push_back(std::move(j));
  }
  return out;
}

/// The arm's kinematic tree for the page (joint placements, axes, limits, the TCP frame).
json armJson(const experiments::ArmKinematics& arm) {
  const multibody::Model& m = *arm.model;
  json a;
  a["name"] = m.name;
  a["joints"] = json::array();
  for (int i = 0; i < m.nq; ++i) {
    const auto k = static_cast<size_t>(i);
    json j;
    j["name"] = m.joint_names[k];
    j["parent"] = m.parents[k];
    j["origin"] = placementJson(m.joint_placements[k]);
    j["axis"] = {m.axes[k].x(), m.axes[k].y(), m.axes[k].z()};
    j["prismatic"] = m.joint_types[k] == multibody::JointType::Prismatic;
    j["lower"] = number(m.limits[k].lower);
    j["upper"] = number(m.limits[k].upper);
    j["column"] = arm.angle_columns[k];
    a["joints"].push_back(std::move(j));
  }
  const multibody::Frame& tcp = m.frames[static_cast<size_t>(arm.tcp_frame)];
  a["tcp"] = {{"name", tcp.name}, {"joint", tcp.joint}, {"origin", placementJson(tcp.placement)}};
  a["clamped"] = arm.clamped;
  a["visuals"] = json::array();
  return a;
}

/// Animation samples of a run: time and the joint angles (at most `frames` rows, strided), the TCP path by the
/// library's forward kinematics, and the clamp position (the TCP at the first sample) of a clamped arm.
json motionJson(const RunData& run, const experiments::ArmKinematics& arm, int frames, std::string& why) {
  const multibody::Model& m = *arm.model;
  std::vector<int> cols;
  for (const auto& c : arm.angle_columns) {
    const int k = run.col(c);
    if (k < 0) {
      why = "the log has no column '" + c + "' (the angle of a joint of the arm)";
      return nullptr;
    }
    cols.push_back(k);
  }
  const Eigen::Index n = run.data.rows();
  const Eigen::Index stride = std::max<Eigen::Index>(1, (n + frames - 1) / frames);
  json t = json::array(), q = json::array(), path = json::array();  // t: rows of the log
  for (size_t j = 0; j < cols.size(); ++j) q.push_back(json::array());
  multibody::Data data(m);
  Eigen::VectorXd qi(m.nq);
  const Eigen::Index path_stride = std::max<Eigen::Index>(1, n / 2000);
  json clamp = nullptr;
  for (Eigen::Index i = 0; i < n; i += stride) {
    t.push_back(i);
    bool finite = true;
    for (size_t j = 0; j < cols.size(); ++j) {
      qi[static_cast<Eigen::Index>(j)] = run.data(i, cols[j]);
      finite = finite && std::isfinite(qi[static_cast<Eigen::Index>(j)]);
      q[j].push_back(rounded(qi[static_cast<Eigen::Index>(j)], 12));
    }
    if (!finite || (i / stride) % std::max<Eigen::Index>(1, path_stride / stride) != 0) continue;
    multibody::forwardKinematics(m, data, qi);
    multibody::updateFramePlacements(m, data);
    const Eigen::Vector3d p = data.oMf[static_cast<size_t>(arm.tcp_frame)].p;
    if (!p.allFinite()) continue;
    path.push_back({p.x(), p.y(), p.z()});
    if (arm.clamped && clamp.is_null()) clamp = {p.x(), p.y(), p.z()};
  }
  json out;
  out["rows"] = std::move(t);
  out["q"] = std::move(q);
  out["tcp_path"] = std::move(path);
  out["clamp"] = std::move(clamp);
  return out;
}

/// The summary for the side panel: the whole summary.json without its column list (the plots show the columns).
json summaryJson(const RunData& run) {
  if (!run.summary) return json::object();
  json s = *run.summary;
  if (s.is_object()) s.erase("columns");
  return s;
}

/// What decides a run's arm: its experiment type and robot file (`robot` of its document).
std::string armKey(const RunData& run) {
  std::string key = run.type;
  if (run.summary)
    if (auto p = run.summary->find("parameters"); p != run.summary->end() && p->is_object())
      if (auto c = p->find("config"); c != p->end() && c->is_object() && c->contains("robot"))
        key += "|" + (*c)["robot"].dump();
  return key;
}

struct ArmSource {
  std::shared_ptr<experiments::Experiment> experiment;
  std::optional<experiments::ArmKinematics> arm;
  std::string why;  ///< why there is no arm
};

ArmSource armOf(const RunData& run) {
  ArmSource a;
  a.experiment = rebuildExperiment(run, a.why);
  if (!a.experiment) return a;
  a.arm = a.experiment->arm();
  if (!a.arm) {
    a.why = "experiment type '" + run.type + "' simulates no arm";
    return a;
  }
  if (!a.arm->model || a.arm->model->nq == 0 || a.arm->angle_columns.size() != static_cast<size_t>(a.arm->model->nq) ||
      a.arm->tcp_frame < 0 || a.arm->tcp_frame >= static_cast<int>(a.arm->model->frames.size())) {
    a.why = "the arm of experiment type '" + run.type + "' is incomplete";
    a.arm.reset();
  }
  return a;
}

/// Replaces every "rows" array of a run's page data (log rows of plotted samples and animation frames) by "xi",
/// indices into one "time" array of the run holding the time of every row used, once.
void compactTimes(json& r, const RunData& d) {
  std::vector<json*> lists;
  for (auto& f : r["figures"])
    for (auto& p : f["panels"])
      for (auto& s : p["series"])
        if (s.contains("rows")) lists.push_back(&s);
  if (r.contains("motion")) lists.push_back(&r["motion"]);
  if (r.contains("key") && r["key"].contains("rows")) lists.push_back(&r["key"]);
  std::vector<Eigen::Index> used;
  for (json* l : lists)
    for (const auto& i : (*l)["rows"]) used.push_back(i.get<Eigen::Index>());
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  json time = json::array();
  for (Eigen::Index i : used) time.push_back(number(d.data(i, d.time())));
  for (json* l : lists) {
    json xi = json::array();
    for (const auto& i : (*l)["rows"])
      xi.push_back(std::lower_bound(used.begin(), used.end(), i.get<Eigen::Index>()) - used.begin());
    l->erase("rows");
    (*l)["xi"] = std::move(xi);
  }
  r["time"] = std::move(time);
}

json runJson(const RunFolder& run, const std::string& label, const ArmSource& arm, const ViewOptions& o,
             bool with_figures, std::string& why, std::map<std::string, std::string>& hashes) {
  json r;
  r["name"] = label;
  r["experiment"] = run.data.experiment;
  r["type"] = run.data.type;
  r["status"] = run.data.status;
  r["csv"] = run.csv;
  r["summary"] = summaryJson(run.data);
  r["changed_inputs"] = changedInputs(run.data, hashes);
  if (arm.arm) {
    json m = motionJson(run.data, *arm.arm, o.frames, why);
    if (!m.is_null()) r["motion"] = std::move(m);
  }
  // A run page: every figure, opening on the one that characterises the type. A sweep: per run only that figure
  // (overlaid across the runs by the page), to keep the page small.
  r["figures"] = json::array();
  const auto figs = figuresOf(run.data);
  const int primary = primaryFigure(figs);
  if (with_figures) {
    for (const auto& f : figs) r["figures"].push_back(figureJson(f, run.data, o.columns));
    r["first_figure"] = std::max(primary, 0);
  } else if (primary >= 0) {
    r["figures"].push_back(figureJson(figs[static_cast<size_t>(primary)], run.data, o.columns));
  }
  return r;
}

/// JSON text that is inert inside a <script> element: '<', '>', '&' (and the line separators JavaScript once
/// rejected in strings) escaped; they can only occur inside JSON strings, where the escapes mean the same.
std::string inertJson(const json& j) {
  const std::string text = j.dump(-1, ' ', false, json::error_handler_t::replace);
  std::string out;
  out.reserve(text.size() + text.size() / 16);
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '<')
      out += "\\u003c";
    else if (c == '>')
      out += "\\u003e";
    else if (c == '&')
      out += "\\u0026";
    else if (c == '\xe2' && i + 2 < text.size() && text[i + 1] == '\x80' &&
             (text[i + 2] == '\xa8' || text[i + 2] == '\xa9')) {
      out += text[i + 2] == '\xa8' ? "\\u2028" : "\\u2029";
      i += 2;
    } else {
      out += c;
    }
  }
  return out;
}

/// The template with every @KEY@ replaced by its value, in one pass: an inserted text (a library, the data, the
/// title) is never scanned for placeholders. Error when the template names a key without a value.
std::string fillTemplate(std::string_view tpl, const std::map<std::string, std::string_view>& values) {
  std::string out;
  size_t pos = 0;
  for (auto at = tpl.find('@'); at != std::string_view::npos; at = tpl.find('@', pos)) {
    const auto end = tpl.find('@', at + 1);
    const auto it =
        end == std::string_view::npos ? values.end() : values.find(std::string(tpl.substr(at + 1, end - at - 1)));
    if (it == values.end()) {  // a lone '@' of the template's own text
      out.append(tpl.substr(pos, at + 1 - pos));
      pos = at + 1;
      continue;
    }
    out.append(tpl.substr(pos, at - pos)).append(it->second);
    pos = end + 1;
  }
  return out.append(tpl.substr(pos));
}

std::string page(const json& data, const std::string& title, const std::vector<std::string>& mesh_formats) {
  const std::string payload = inertJson(data);
  const std::string nonce = io::contentHash(payload).substr(5);
  // The mesh loaders the page needs (three.js's, r111), each in a script element of its own.
  std::string loaders;
  auto script = [&](std::string_view code) {
    loaders.append("<script nonce=\"").append(nonce).append("\">").append(code).append("</script>\n");
  };
  for (const auto& f : mesh_formats) {
    if (f == "stl") script(assets::kStlLoaderJs);
    if (f == "obj") script(assets::kObjLoaderJs);
    if (f == "dae") {
      script(assets::kTgaLoaderJs);
      script(assets::kColladaLoaderJs);
    }
  }
  // The title is the only data-derived text outside the JSON: it goes in escaped as text.
  std::string esc;
  for (char c : title) {
    if (c == '<')
      esc += "&lt;";
    else if (c == '>')
      esc += "&gt;";
    else if (c == '&')
      esc += "&amp;";
    else if (c == '"')
      esc += "&quot;";
    else if (static_cast<unsigned char>(c) >= 0x20)
      esc += c;
  }
  const std::string style = std::string(assets::kUplotCss) + "\n" + std::string(assets::kViewerCss);
  return fillTemplate(assets::kViewerHtml, {{"TITLE", esc},
                                            {"NONCE", nonce},
                                            {"STYLE", style},
                                            {"DATA", payload},
                                            {"THREE", assets::kThreeJs},
                                            {"ORBIT", assets::kOrbitControlsJs},
                                            {"LOADERS", loaders},
                                            {"UPLOT", assets::kUplotJs},
                                            {"APP", assets::kViewerJs}});
}

void checkOptions(const ViewOptions& o) {
  if (o.columns < 10 || o.columns > 100000)
    throw InputError("view: columns " + std::to_string(o.columns) + ": expected 10 to 100000 slices per series");
  if (o.mesh_bytes < 0) throw InputError("view: mesh budget " + std::to_string(o.mesh_bytes) + ": expected >= 0");
  if (o.frames < 10 || o.frames > 10000000)
    throw InputError("view: frames " + std::to_string(o.frames) + ": expected 10 to 10000000 animation samples");
}

}  // namespace

std::string viewHtml(const std::string& dir_in, const ViewOptions& options) {
  checkOptions(options);
  const OutputFolder folder = outputFolder(dir_in);
  const fs::path dir = folder.path;
  const bool is_run = folder.is_run;
  json data;
  data["format"] = "jointsim-view 1";
  data["kind"] = is_run ? "run" : "sweep";
  data["runs"] = json::array();
  data["notes"] = json::array();
  std::string title = options.title;
  ArmSource arm;
  std::map<std::string, std::string> hashes;
  if (is_run) {
    const RunFolder run = loadRunFolder(dir.string());
    arm = armOf(run.data);
    std::string why;
    json r = runJson(run, run.data.experiment, arm, options, true, why, hashes);
    if (!why.empty()) r["motion_note"] = why;
    compactTimes(r, run.data);
    data["runs"].push_back(std::move(r));
    if (title.empty()) title = run.data.experiment;
  } else {
    const auto rows = readManifest((dir / "manifest.csv").string());
    json key = nullptr;
    bool first = true;
    std::string arm_key;
    for (const ManifestRow& row : rows) {
      json r;
      const auto folder = runFolder(dir.string(), row);
      std::optional<RunFolder> run;
      if (folder) try {
          run = loadRunFolder(*folder);
        } catch (const InputError&) {
          // Not the message: it may quote the lines of whatever file a hand-edited summary names as the log.
          r["error"] = "its folder has no readable summary.json and log (jointsim view on the folder says why)";
        }
      if (run && first) {
        arm = armOf(run->data);
        arm_key = armKey(run->data);
        first = false;
      }
      std::string why;
      if (run) {
        // The page draws one arm: the first run's. A run on another robot is not animated.
        ArmSource none;
        none.why = "its robot differs from the first run's (the page draws one arm; jointsim view on its folder)";
        const bool same_arm = armKey(run->data) == arm_key;
        r = runJson(*run, row.run, same_arm ? arm : none, options, false, why, hashes);
        if (!same_arm && arm.arm) why = none.why;
        if (!why.empty()) r["motion_note"] = why;
        // The key signal of the sweep (the first run's type decides it), decimated with its peaks.
        if (key.is_null())
          if (auto k = keySignal(run->data))
            key = {
                {"x", k->x},           {"y", k->y},           {"y_minus", k->y_minus}, {"factor", k->factor},
                {"xlabel", k->xlabel}, {"ylabel", k->ylabel}, {"what", k->what},       {"unit", labelUnit(k->ylabel)}};
        if (!key.is_null()) {
          const RunData& d = run->data;
          const int x = d.col(key["x"].get<std::string>()), y = d.col(key["y"].get<std::string>());
          const std::string ym_name = key["y_minus"].get<std::string>();
          const int ym = ym_name.empty() ? -2 : d.col(ym_name);
          if (x >= 0 && y >= 0 && ym != -1) {
            Eigen::VectorXd v = d.data.col(y);
            if (ym >= 0) v -= d.data.col(ym);
            v *= key["factor"].get<double>();
            json kx = json::array(), ky = json::array();
            const bool timed = x == d.time();
            for (Eigen::Index i : peakRows(v, options.columns)) {
              kx.push_back(timed ? json(i) : plotted(d.data(i, x)));
              ky.push_back(plotted(v[i]));
            }
            r["key"] = {{timed ? "rows" : "x", std::move(kx)}, {"y", std::move(ky)}};
          }
        }
        compactTimes(r, run->data);
      } else {
        r["name"] = row.run;
        if (!r.contains("error")) r["error"] = "no run folder with a summary.json found";
      }
      r["status"] = row.status;
      json labels = json::array();
      for (const auto& [k, v] : row.extra)
        if (k.rfind("fault_", 0) == 0 || k == "design" || k == "seed" || k == "label") labels.push_back({k, v});
      r["labels"] = std::move(labels);
      r["overrides"] = row.overrides;
      data["runs"].push_back(std::move(r));
    }
    data["key"] = key;
    if (title.empty()) title = dir.filename().string();
  }
  std::vector<std::string> formats;
  if (arm.arm) {
    data["arm"] = armJson(*arm.arm);
    data["arm"]["visuals"] = visualsJson(*arm.arm->model, options.mesh_bytes, formats, data["notes"]);
  } else {
    data["arm"] = nullptr;
  }
  data["arm_note"] = arm.why;
  data["title"] = title;
  return page(data, title, formats);
}

std::string writeView(const std::string& dir, const std::string& output, const ViewOptions& options) {
  const std::string html = viewHtml(dir, options);
  const std::string path = output.empty() ? (fs::path(dir) / "view.html").string() : output;
  const fs::path parent = fs::absolute(path).parent_path();
  if (!io::isDirectory(parent.string())) io::createDirectories(parent.string());
  io::writeFileAtomically(path, html);
  return path;
}

}  // namespace jointsim::report
