// Agreement of a run with a measured log (report/agreement.hpp).
#include "jointsim/report/agreement.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include <nlohmann/json.hpp>

#include "jointsim/common/error.hpp"
#include "jointsim/common/text.hpp"
#include "jointsim/io/output.hpp"
#include "jointsim/report/plot.hpp"
#include "report/gnuplot.hpp"

namespace jointsim::report {
namespace {

namespace fs = std::filesystem;

std::string fmt(double v) { return formatNumber(v, 6); }

/// The time column: `time` (any unit) or `t_s`, else the first column.
int logTimeColumn(const io::CsvTable& t) {
  for (const char* name : {"time", "t_s", "t"}) {
    const int c = t.find(name);
    if (c >= 0) return c;
  }
  return 0;
}

/// Linear interpolation of column `c` of `t` (time column `tc`, increasing) at time x inside its range.
double interpolateColumn(const io::CsvTable& t, int tc, int c, double x) {
  const auto col = t.data.col(tc);
  const Eigen::Index n = t.rows();
  const double* b = col.data();
  Eigen::Index k = static_cast<Eigen::Index>(std::upper_bound(b, b + n, x) - b) - 1;
  k = std::clamp<Eigen::Index>(k, 0, n - 2);
  const double w = (x - b[k]) / (b[k + 1] - b[k]);
  return (1.0 - w) * t.data(k, c) + w * t.data(k + 1, c);
}

}  // namespace

SignalPair SignalPair::parse(const std::string& text, const std::string& what) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size() || text.find('=', eq + 1) != std::string::npos)
    throw InputError(what +
                     ": expected PREDICTED=MEASURED (a column of the run's log, one of the measured log), got '" +
                     text + "'");
  return {trim(text.substr(0, eq)), trim(text.substr(eq + 1))};
}

std::vector<SignalPair> SignalPair::expand(const std::string& text, const std::vector<std::string>& joint_names,
                                           const std::string& what) {
  const SignalPair base = parse(text, what);
  const bool placeholders = text.find("{joint}") != std::string::npos || text.find("{j}") != std::string::npos ||
                            text.find("{i}") != std::string::npos;
  if (!placeholders) return {base};
  if (joint_names.empty())
    throw InputError(what + ": '" + text + "' has {joint}, {j} or {i} placeholders: give the joint names too");
  auto sub = [](std::string s, const std::string& key, const std::string& value) {
    for (size_t p = s.find(key); p != std::string::npos; p = s.find(key, p + value.size()))
      s.replace(p, key.size(), value);
    return s;
  };
  std::vector<SignalPair> out;
  for (size_t k = 0; k < joint_names.size(); ++k) {
    auto one = [&](const std::string& s) {
      return sub(sub(sub(s, "{joint}", joint_names[k]), "{j}", std::to_string(k + 1)), "{i}", std::to_string(k));
    };
    out.push_back({one(base.predicted), one(base.measured)});
  }
  return out;
}

AgreementResult agreement(const io::CsvTable& predicted, const io::CsvTable& measured,
                          const std::vector<SignalPair>& pairs, const AgreementOptions& o) {
  if (pairs.empty()) throw InputError("agreement: no signal pairs given (PREDICTED=MEASURED)");
  if (!std::isfinite(o.time_offset)) throw InputError("agreement: the time offset must be finite");
  if (!(o.max_lag >= 0.0 && std::isfinite(o.max_lag)))
    throw InputError("agreement: the largest lag must be >= 0 s, got " + fmt(o.max_lag));
  if (!(o.t_begin < o.t_end)) throw InputError("agreement: the time window must have t_begin < t_end");
  const int tp = logTimeColumn(predicted), tm = logTimeColumn(measured);
  io::checkedTimes(predicted, tp);
  io::checkedTimes(measured, tm);
  // Measured samples whose shifted time lies inside the run, for every lag searched.
  const double p0 = predicted.data(0, tp), p1 = predicted.data(predicted.rows() - 1, tp);
  std::vector<Eigen::Index> rows, rows_lag;
  for (Eigen::Index r = 0; r < measured.rows(); ++r) {
    const double t = measured.data(r, tm);
    if (t < o.t_begin || t > o.t_end) continue;
    const double x = t - o.time_offset;
    if (x >= p0 && x <= p1) rows.push_back(r);
    if (x - o.max_lag >= p0 && x + o.max_lag <= p1) rows_lag.push_back(r);
  }
  if (rows.size() < 3)
    throw InputError(measured.path + ": only " + std::to_string(rows.size()) +
                     " measured samples lie inside the run (" + fmt(p0 + o.time_offset) + " … " +
                     fmt(p1 + o.time_offset) + " s in log time): check the time offset and window");
  double dt = std::numeric_limits<double>::infinity();
  for (Eigen::Index r = 1; r < measured.rows(); ++r) dt = std::min(dt, measured.data(r, tm) - measured.data(r - 1, tm));

  AgreementResult res;
  res.predicted_path = predicted.path;
  res.measured_path = measured.path;
  res.t_begin = measured.data(rows.front(), tm);
  res.t_end = measured.data(rows.back(), tm);
  for (const SignalPair& sp : pairs) {
    const int cp = predicted.require(sp.predicted, "the predicted signal");
    const int cm = measured.require(sp.measured, "the measured signal");
    PairAgreement a;
    a.pair = sp;
    a.samples = static_cast<long>(rows.size());
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    double se = 0, sb = 0, sp_ = 0, sm = 0, spp = 0, smm = 0, spm = 0;
    for (Eigen::Index r : rows) {
      const double m = measured.data(r, cm),
                   p = interpolateColumn(predicted, tp, cp, measured.data(r, tm) - o.time_offset);
      const double e = p - m;
      lo = std::min(lo, m);
      hi = std::max(hi, m);
      se += e * e;
      sb += e;
      a.max_abs = std::max(a.max_abs, std::abs(e));
      sp_ += p;
      sm += m;
      spp += p * p;
      smm += m * m;
      spm += p * m;
    }
    const double N = static_cast<double>(rows.size());
    a.range = hi - lo;
    if (!(a.range > 0.0))
      throw InputError(measured.path + ": column '" + measured.header[static_cast<size_t>(cm)] +
                       "' is constant over the compared samples: no range to scale the error by");
    a.rms = std::sqrt(se / N);
    a.rms_percent = 100.0 * a.rms / a.range;
    a.bias = sb / N;
    const double vp = spp / N - (sp_ / N) * (sp_ / N), vm = smm / N - (sm / N) * (sm / N);
    a.correlation = vp > 0.0 && vm > 0.0 ? (spm / N - (sp_ / N) * (sm / N)) / std::sqrt(vp * vm) : 0.0;
    // Best-fit lag: p(t − τ) against m(t) on the samples valid for every τ.
    a.lag = 0.0;
    a.rms_percent_at_lag = a.rms_percent;
    if (o.max_lag > 0.0 && rows_lag.size() >= 3) {
      // Steps of a quarter sample, at most 1000 each way (a log with a tiny time step or a long max_lag stays quick).
      const double step = std::max(dt / 4.0, o.max_lag / 1000.0);
      const long K = static_cast<long>(std::floor(o.max_lag / step + 1e-9));
      double best = std::numeric_limits<double>::infinity();
      for (long k = -K; k <= K; ++k) {
        const double tau = static_cast<double>(k) * step;
        double s = 0;
        for (Eigen::Index r : rows_lag) {
          const double e =
              interpolateColumn(predicted, tp, cp, measured.data(r, tm) - o.time_offset - tau) - measured.data(r, cm);
          s += e * e;
        }
        if (s < best) {
          best = s;
          a.lag = tau;
        }
      }
      a.rms_percent_at_lag = 100.0 * std::sqrt(best / static_cast<double>(rows_lag.size())) / a.range;
    }
    res.pairs.push_back(a);
  }
  return res;
}

AgreementResult agreementOfFiles(const std::string& predicted_csv, const std::string& measured_csv,
                                 const std::vector<SignalPair>& pairs, const AgreementOptions& options) {
  return agreement(io::readCsv(predicted_csv), io::readCsv(measured_csv), pairs, options);
}

std::string formatAgreement(const AgreementResult& r) {
  std::ostringstream os;
  os << "predicted: " << r.predicted_path << "\nmeasured:  " << r.measured_path
     << "\ncompared:  " << (r.pairs.empty() ? 0 : r.pairs.front().samples) << " measured samples, log time "
     << fmt(r.t_begin) << " … " << fmt(r.t_end) << " s\n";
  char line[512];
  std::snprintf(line, sizeof line, "%-34s %-16s %9s %11s %11s %11s %7s %9s %9s\n", "predicted", "measured", "rms[%R]",
                "rms", "bias", "max|e|", "corr", "lag[s]", "rms@lag");
  os << line;
  for (const PairAgreement& a : r.pairs) {
    std::snprintf(line, sizeof line, "%-34s %-16s %9.2f %11.4g %11.4g %11.4g %7.3f %9.4f %9.2f\n",
                  a.pair.predicted.c_str(), a.pair.measured.c_str(), a.rms_percent, a.rms, a.bias, a.max_abs,
                  a.correlation, a.lag, a.rms_percent_at_lag);
    os << line;
  }
  os << "rms[%R]: RMS of predicted − measured in % of the measured range R; lag > 0: the measurement comes later\n";
  return os.str();
}

std::string agreementJson(const AgreementResult& r) {
  nlohmann::ordered_json j;
  j["predicted"] = r.predicted_path;
  j["measured"] = r.measured_path;
  j["t_begin_s"] = r.t_begin;
  j["t_end_s"] = r.t_end;
  j["pairs"] = nlohmann::ordered_json::array();
  for (const PairAgreement& a : r.pairs)
    j["pairs"].push_back({{"predicted", a.pair.predicted},
                          {"measured", a.pair.measured},
                          {"samples", a.samples},
                          {"range", a.range},
                          {"rms", a.rms},
                          {"rms_percent", a.rms_percent},
                          {"bias", a.bias},
                          {"max_abs", a.max_abs},
                          {"correlation", a.correlation},
                          {"lag_s", a.lag},
                          {"rms_percent_at_lag", a.rms_percent_at_lag}});
  return j.dump(2) + "\n";
}

std::vector<std::string> plotAgreement(const io::CsvTable& pred, const io::CsvTable& meas,
                                       const AgreementResult& result, const AgreementOptions& options,
                                       const std::string& fig_dir, const std::string& gnuplot) {
  const std::string exe = findGnuplot(gnuplot);
  const int tp = logTimeColumn(pred), tm = logTimeColumn(meas);
  const fs::path out = fs::absolute(fig_dir).lexically_normal();
  io::createDirectories(out.string());
  std::ostringstream body;
  body << "# Agreement figures written by `jointsim agreement` (docs/replay.md).\n" << gp::kLineTypes;
  std::vector<std::string> finals;
  int k = 0;
  for (const PairAgreement& a : result.pairs) {
    ++k;
    const int cp = pred.require(a.pair.predicted, "the predicted signal");
    const int cm = meas.require(a.pair.measured, "the measured signal");
    // Datablocks: measured, predicted (shifted to log time) and the error at the measured samples.
    std::ostringstream m, p, e;
    const double p0 = pred.data(0, tp) + options.time_offset, p1 = pred.data(pred.rows() - 1, tp) + options.time_offset;
    for (Eigen::Index r = 0; r < meas.rows(); ++r) {
      const double t = meas.data(r, tm);
      if (t < result.t_begin || t > result.t_end) continue;
      m << fmt(t) << "," << fmt(meas.data(r, cm)) << "\n";
      if (t >= p0 && t <= p1)
        e << fmt(t) << "," << fmt(interpolateColumn(pred, tp, cp, t - options.time_offset) - meas.data(r, cm)) << "\n";
    }
    for (Eigen::Index r = 0; r < pred.rows(); ++r) {
      const double t = pred.data(r, tp) + options.time_offset;
      if (t >= result.t_begin && t <= result.t_end) p << fmt(t) << "," << fmt(pred.data(r, cp)) << "\n";
    }
    const std::string id = std::to_string(k);
    body << "$meas" << id << " << EOD\n"
         << m.str() << "EOD\n$pred" << id << " << EOD\n"
         << p.str() << "EOD\n$err" << id << " << EOD\n"
         << e.str() << "EOD\n";
    gp::Figure f;
    std::string stem = "agreement_" + id + "_" + a.pair.measured;
    for (char& c : stem)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') c = '_';
    f.stem = stem;
    f.title = a.pair.predicted + " vs measured " + a.pair.measured + ": RMS " + fmt(a.rms_percent) +
              " % of range, r = " + fmt(a.correlation) + ", lag " + fmt(a.lag) + " s";
    f.rows = 2;
    gp::Panel top;
    top.title = "measured and predicted";
    top.xlabel = "log time [s]";
    top.ylabel = a.pair.measured;
    top.series.push_back({"$meas" + id, "1:2", "measured " + a.pair.measured, "lines", 0, false, false});
    top.series.push_back({"$pred" + id, "1:2", "predicted " + a.pair.predicted, "lines", 0, false, false});
    gp::Panel bottom;
    bottom.title = "error predicted − measured";
    bottom.xlabel = "log time [s]";
    bottom.ylabel = "error";
    bottom.key = experiments::Key::none;
    bottom.series.push_back({"$err" + id, "1:2", "", "lines", 0, false, false});
    f.panels = {top, bottom};
    const std::string path = (out / (f.stem + ".png")).string();
    body << gp::renderFigure(f,
                             "set terminal pngcairo size 1400,900 noenhanced font 'DejaVu Sans,11' linewidth 1 "
                             "background rgb 'white'",
                             path, 1.0);
    finals.push_back(path);
  }
  gp::runScript(exe, body.str(), finals, out.string(), "the agreement figures");
  return finals;
}

}  // namespace jointsim::report
