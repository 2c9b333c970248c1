#pragma once
/// \file
/// The interactive viewer of a run or sweep folder (`jointsim view`): one self-contained HTML page that opens offline
/// in a current browser, without a server. It shows the arm animated in 3D from the logged joint angles and the
/// model's kinematics (link frames and simple link geometry, the tool centre point and its path, the clamp of a
/// clamping run, a gauge per joint with its limits), with play/pause, speed, a time slider and an orbiting camera;
/// the figures of the experiment type (experiments/registry.hpp, the same descriptions `jointsim plot` draws) as
/// interactive plots (zoom by dragging, double-click to reset, a cursor readout with units) whose cursor and the
/// animation follow each other; for a sweep, the runs with their labels (fault, design, seed) in a list, the key
/// signal of every run overlaid and the selected run animated; the summary in a side panel.
///
/// The page embeds its browser code (three.js r111 and uPlot, see third_party_notes.md) and its data as JSON in an
/// inert `<script type="application/json">` element with every '<', '>' and '&' escaped; the page script puts any
/// data-derived text into the page as text (textContent), never as markup, and a Content-Security-Policy allows only
/// the page's own scripts (by nonce) and no network access. Long logs are decimated for display with their peaks
/// kept: per plotted series, the rows of its minimum and maximum in each of `ViewOptions::columns` equal slices, so
/// every drawn point is a row of the CSV. The page's script interface, `window.jointsimView`, is what the browser
/// tests drive (tests/python/test_view_browser.py; docs/view.md).

#include <string>

namespace jointsim::report {

struct ViewOptions {
  int columns = 1000;  ///< slices per plotted series for min/max decimation (about the pixel width), 10..100000
  int frames = 20000;  ///< most animation samples per run (rows are strided beyond it), 10..10000000
  std::string title;   ///< page title (empty: the experiment's or sweep folder's name)
  /// Most bytes of URDF visual meshes (STL, OBJ, COLLADA) embedded in the page; meshes beyond are listed as not drawn.
  long mesh_bytes = 50'000'000;
};

/// The page of the run folder (summary.json + CSV log of `jointsim run`) or sweep folder (manifest.csv of
/// `jointsim batch`) `dir`, as HTML text; nothing is written. The arm is rebuilt from the summary's experiment
/// document (parameters.config, with the files it names as they are now); when that fails the page says why and
/// shows the plots and summary without the 3D view. InputError (CLI exit 2) for a folder that is neither, a run
/// without a log, unreadable files or bad options.
std::string viewHtml(const std::string& dir, const ViewOptions& options = {});

/// Writes viewHtml(dir) to `output` (empty: DIR/view.html) through a temporary file renamed into place, and returns
/// the path written.
std::string writeView(const std::string& dir, const std::string& output = {}, const ViewOptions& options = {});

}  // namespace jointsim::report
