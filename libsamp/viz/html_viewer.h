// Self-contained interactive viewers as one HTML file (`samp view`, `samp fit
// --html`, `samp inspect --html`; docs/fitting.md "Viewer"). The page inlines
// three.js (Debian's libjs-three, embedded into samp at build time), its orbit
// controls and the scene data (JSON with binary arrays in base64), so it opens
// from disk without a server or network.
//   fit page:     per frame the stereo points of every track (colour by track),
//                 the fitted mesh at that frame's pose, the trajectories, the
//                 detections, the road plane; frame slider and play button,
//                 orbit camera, a track panel (click = focus); with ground
//                 truth the true boxes and the surfaces coloured by error.
//   inspect page: the mean shape and a slider per eigen-shape; the surface is
//                 extracted in the page (three.js' marching cubes) from
//                 mu + sum z_i w_i on the model grid.
// Pages carry a self-test (open with #selftest) that the browser test reads.
// Pure functions; files are written atomically.
#pragma once

#include <string>

#include "libsamp/model/shape_model.h"
#include "libsamp/viz/fit_run.h"

namespace samp {

// True when this build embeds three.js (the pages cannot be written otherwise).
bool HtmlViewerAvailable();
// The three.js revision embedded (e.g. "111"), "" when none.
std::string EmbeddedThreeRevision();

struct FitHtmlOptions {
  std::string title;               // page title; "" = "samp fit: <output_dir>"
  int max_points_per_frame = 0;    // per track and frame, 0 = all (a seeded, even subsample otherwise)

  void Check() const;
};

// The page as a string, and written to `path`. Throw samp::Error when this
// build has no three.js or the options are invalid.
std::string FitViewerHtml(const FitRunView& run, const FitHtmlOptions& options = {});
void WriteFitViewer(const std::string& path, const FitRunView& run, const FitHtmlOptions& options = {});

struct InspectHtmlOptions {
  std::string title;               // "" = "samp inspect: <model path>"
  std::string model_path;          // shown on the page
  int max_components = 0;          // sliders, 0 = all R
  double slider_sigmas = 3.0;      // slider range +-this many sigma_i (> 0)

  void Check() const;
};

std::string InspectViewerHtml(const ShapeModel& model, const InspectHtmlOptions& options = {});
void WriteInspectViewer(const std::string& path, const ShapeModel& model, const InspectHtmlOptions& options = {});

// Base64 of raw bytes (RFC 4648, with padding); exposed for tests.
std::string Base64Encode(const void* data, size_t size);

}  // namespace samp
