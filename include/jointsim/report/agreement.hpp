#pragma once
/// \file
/// Agreement of a run with a measurement (`jointsim agreement`, Python `jointsim.agreement`; docs/replay.md): how
/// well predicted signals (a run's CSV log) reproduce measured ones (a robot log), pair by pair: the RMS error in
/// % of the measured signal's range, the correlation, and the lag that fits best.
///
/// Alignment: the measured log's samples are the reference grid. Each measured sample at log time t_m is compared
/// with the prediction at run time t_m − offset (`time_offset`: the log time of the run's t = 0, e.g. the replay's
/// `start_time`), linearly interpolated between the run's samples; measured samples outside the run (or outside
/// [t_begin, t_end] in log time) are left out. Time columns: the column named `time` (any unit) or `t_s`, else the
/// first column.
///
/// Per pair, with e_k = p_k − m_k over the N compared samples and R = max m − min m:
///   rms = √(Σ e_k²/N), rms_percent = 100 rms/R, bias = Σ e_k/N, max_abs = max |e_k|,
///   correlation = Pearson's r of (p, m),
///   lag = the τ in [−max_lag, max_lag] (steps of a quarter of the measured sample interval, at most 1000 steps each
///   way) that minimises the
///   RMS of p(t − τ) − m(t) over the samples where every shifted prediction exists; τ > 0: the measurement comes
///   later than the prediction (a measured current lagging its model by one sample: τ ≈ +8 ms at 125 Hz).

#include <limits>
#include <string>
#include <vector>

#include "jointsim/io/csv_reader.hpp"

namespace jointsim::report {

/// One predicted signal against one measured signal.
struct SignalPair {
  std::string predicted;  ///< column of the run's log (with or without `[unit]`)
  std::string measured;   ///< column of the measured log (with or without `[unit]`)
  /// Parses "PREDICTED=MEASURED" (InputError naming `what` on anything else).
  static SignalPair parse(const std::string& text, const std::string& what = "pair");
  /// Expands a pair with placeholders once per joint: `{joint}` becomes joint_names[k], `{j}` k + 1 and `{i}` k
  /// (e.g. "current_{joint}=i_actual_{j}"); a pair without placeholders is returned as it is. InputError when it has
  /// placeholders but no joint names are given.
  static std::vector<SignalPair> expand(const std::string& text, const std::vector<std::string>& joint_names,
                                        const std::string& what = "pair");
};

struct AgreementOptions {
  double time_offset = 0.0;                                   ///< log time of the run's t = 0 [s]
  double max_lag = 0.05;                                      ///< lags searched, ±[s] (0: no search)
  double t_begin = -std::numeric_limits<double>::infinity();  ///< compare measured samples from this log time [s]
  double t_end = std::numeric_limits<double>::infinity();     ///< ... up to this log time [s]
};

struct PairAgreement {
  SignalPair pair;
  long samples = 0;                 ///< N, the measured samples compared
  double range = 0.0;               ///< R of the measured signal over them [its unit]
  double rms = 0.0;                 ///< [unit]
  double rms_percent = 0.0;         ///< of R [%]
  double bias = 0.0;                ///< mean of p − m [unit]
  double max_abs = 0.0;             ///< [unit]
  double correlation = 0.0;         ///< Pearson's r [-] (0 when either signal is constant)
  double lag = 0.0;                 ///< best-fit lag τ [s]
  double rms_percent_at_lag = 0.0;  ///< the RMS at τ, in % of R
};

struct AgreementResult {
  std::string predicted_path, measured_path;
  double t_begin = 0.0, t_end = 0.0;  ///< log times of the first and last compared samples [s]
  std::vector<PairAgreement> pairs;
};

/// Compares every pair (see the file comment). InputError (naming the file and the column) for a missing column,
/// time that does not increase, fewer than 3 compared samples, a measured signal without range, bad options.
AgreementResult agreement(const io::CsvTable& predicted, const io::CsvTable& measured,
                          const std::vector<SignalPair>& pairs, const AgreementOptions& options = {});
/// Reads both files (io::readCsv) and compares them.
AgreementResult agreementOfFiles(const std::string& predicted_csv, const std::string& measured_csv,
                                 const std::vector<SignalPair>& pairs, const AgreementOptions& options = {});

/// A table: one line per pair (RMS in % of range, RMS, bias, max, correlation, lag, RMS at the lag).
std::string formatAgreement(const AgreementResult& result);
/// The same as JSON text (an object with the files, the time range and a list `pairs`).
std::string agreementJson(const AgreementResult& result);

/// Writes one figure per pair of `result` (made from these tables) into `fig_dir` (created): measured and predicted over log time (upper panel) and the
/// error p − m (lower panel), named agreement_<k>_<measured column>.png; returns the paths. Needs gnuplot
/// (report/plot.hpp: findGnuplot); figures appear only when gnuplot succeeded (temporary names, then renamed).
std::vector<std::string> plotAgreement(const io::CsvTable& predicted, const io::CsvTable& measured,
                                       const AgreementResult& result, const AgreementOptions& options,
                                       const std::string& fig_dir, const std::string& gnuplot = {});

}  // namespace jointsim::report
