// `jointsim compare A.csv B.csv [--rtol R] [--atol A] [--time-tol D] [--columns ...]`: compares two logs aligned
// on time (B interpolated onto A's times where B has no sample there) and prints per column the largest
// deviation, where it happens and the verdict (docs/regression.md). Exit status 0 when every compared column
// is within tolerance, 1 otherwise (after the table, a jointsim::Error "N of M columns differ ..."), 2 for
// unreadable or incompatible files (InputError).
#include <cstdio>
#include <memory>

#include "cli_common.hpp"
#include "jointsim/common/error.hpp"
#include "jointsim/report/compare.hpp"

namespace jointsim::cli {

void addCompareCommand(CLI::App& app) {
  struct Options {
    std::string a, b;
    report::CompareOptions compare;
    bool quiet = false;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Compare two CSV logs on time: exit 0 when every column is within tolerance, 1 when one is not, 2 for "
                 "unreadable or incompatible files");
  cmd->add_option("a", opt->a, "Reference log (CSV; time = the column named time, else the first column)")->required();
  cmd->add_option("b", opt->b, "Log to check (CSV), interpolated linearly onto A's times where needed")->required();
  cmd->add_option("--rtol", opt->compare.rtol,
                  "Relative tolerance, times the column's peak magnitude (default 1e-6): |a-b| <= atol + rtol*peak");
  cmd->add_option("--atol", opt->compare.atol, "Absolute tolerance in the column's unit (default 1e-12)");
  cmd->add_option("--time-tol", opt->compare.time_tolerance,
                  "Accept B's values within +-D seconds of A's sample time (a tube for shifted events; default 0)");
  cmd->add_option("--time-range-tol", opt->compare.time_range_tolerance,
                  "Largest difference of the first/last times of A and B [s] (default: one sample interval of the "
                  "coarser log)");
  cmd->add_option("--columns", opt->compare.columns,
                  "Columns to compare, comma-separated or repeated, with or without [unit] (default: all of A)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_flag("-q,--quiet", opt->quiet, "List only the columns out of tolerance (and the verdict)");
  cmd->callback([opt] {
    const report::CompareResult r = report::compareCsvFiles(opt->a, opt->b, opt->compare);
    std::fputs(report::formatComparison(r, opt->quiet).c_str(), stdout);
    std::fflush(stdout);
    if (!r.pass()) {
      std::string list;
      for (const auto& c : r.columns)
        if (!c.pass) list += (list.empty() ? "" : ", ") + c.name;
      throw Error(std::to_string(r.failed()) + " of " + std::to_string(r.columns.size()) +
                  " columns differ beyond tolerance: " + list);
    }
  });
}

}  // namespace jointsim::cli
