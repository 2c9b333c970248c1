// `jointsim plot RUN_DIR [-o FIG_DIR] [--svg]`: figures of a run folder (or a sweep folder) via gnuplot.
#include <cstdio>
#include <memory>

#include "cli_common.hpp"
#include "jointsim/report/plot.hpp"

namespace jointsim::cli {

void addPlotCommand(CLI::App& app) {
  struct Options {
    std::string run_dir, fig_dir;
    report::PlotOptions plot;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "plot", "Draw the figures of a run folder (summary.json + CSV) or a sweep folder (manifest.csv) with gnuplot");
  cmd->add_option("run_dir", opt->run_dir, "Output folder of `jointsim run` or `jointsim batch`")->required();
  cmd->add_option("-o,--output-dir", opt->fig_dir, "Figure folder (default: RUN_DIR/figures)");
  cmd->add_flag("--svg", opt->plot.svg, "Also write an SVG of every figure");
  cmd->add_option("--width", opt->plot.width, "Figure width [pixels]")->capture_default_str();
  cmd->add_option("--height", opt->plot.height, "Figure height [pixels]")->capture_default_str();
  cmd->add_flag("--keep-script", opt->plot.keep_script,
                "Also write FIG_DIR/<name>_plots.gp, the gnuplot script (run it with gnuplot to adjust the figures)");
  cmd->add_option("--gnuplot", opt->plot.gnuplot, "gnuplot executable (default: gnuplot on PATH)");
  cmd->callback([opt] {
    const auto written = report::plotRun(opt->run_dir, opt->fig_dir, opt->plot);
    std::printf("%zu file%s written:\n", written.size(), written.size() == 1 ? "" : "s");
    for (const auto& path : written) std::printf("  %s\n", path.c_str());
  });
}

}  // namespace jointsim::cli
