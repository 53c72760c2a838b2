// Pictures of a fit (`samp fit --pictures`, `samp eval --pictures`,
// docs/fitting.md "Pictures"), drawn with the project's renderer, no display:
//   per track   (a) the fitted mesh in the left image at a few frames, shaded
//                   with its outline, beside the detection box of the frame;
//               (b) bird's-eye views: the stereo points of all frames in the
//                   object frame, aligned by the detections (before) and by
//                   the fitted poses (after; the paper's Figure 5), and the
//                   trajectory in the world with the detections;
//               (c) the shape from three views with its code as bars;
//               (e) with ground truth: the surface coloured by its error.
//   per sequence one bird's-eye sheet of all tracks over the frames.
// Pure functions of their arguments (thread-safe); files are written atomically.
#pragma once

#include <string>
#include <vector>

#include "libsamp/viz/fit_run.h"
#include "libsamp/viz/html_viewer.h"
#include "libsamp/viz/image.h"

namespace samp {

struct FitPictureOptions {
  std::string output_folder;        // pictures go to <output_folder>/<seq>/
  int overlay_frames = 4;           // frames shown in the image overlay (spread over the track), >= 1
  int overlay_cell_width = 260;     // one overlay panel, pixels
  int overlay_cell_height = 190;
  int birdseye_size = 380;          // one bird's-eye panel (square), pixels
  int sequence_sheet_width = 1100;  // the per-sequence sheet, pixels (height follows the scene)
  int shape_cell_width = 300;       // one view of the shape strip, pixels
  int shape_cell_height = 170;
  bool error_surfaces = true;       // track_<id>_error.png when ground truth is known

  void Check() const;               // throws samp::Error naming the field
};

struct FitPictureSummary {
  std::vector<std::string> files;   // written, in order
  std::string BriefReport() const;
};

// (a): rows "detection" and "fit", one column per chosen frame.
RgbImage RenderTrackOverlay(const SequenceView& sequence, const TrackView& track,
                            const FitPictureOptions& options);
// (b): before | after | trajectory.
RgbImage RenderTrackBirdsEye(const SequenceView& sequence, const TrackView& track,
                             const FitPictureOptions& options);
// (c): three-quarter, side and top view, and the code (in sigmas when known).
RgbImage RenderTrackShapeStrip(const TrackView& track, const FitPictureOptions& options);
// (e): two views of the mesh coloured by track.vertex_errors against
// sequence.error_tau, with a colour bar and the share within τ. Throws when
// the track has no errors.
RgbImage RenderTrackErrorSurface(const SequenceView& sequence, const TrackView& track,
                                 const FitPictureOptions& options);
// All tracks of a sequence from above: points, trajectories, footprints, ego path.
RgbImage RenderSequenceBirdsEye(const SequenceView& sequence, const FitPictureOptions& options);

// Writes <seq>/birdseye.png and per track <seq>/track_<id>_{overlay,birdseye,shape}.png
// (+ _error.png with ground truth). A track whose picture fails is logged and
// skipped; invalid options throw.
FitPictureSummary WriteFitPictures(const FitRunView& run, const FitPictureOptions& options);
// Only the error surfaces (for `samp eval`): <seq>/track_<id>_error.png.
FitPictureSummary WriteErrorSurfacePictures(const FitRunView& run, const FitPictureOptions& options);

// ---- Everything for one fit output folder (what `samp fit --pictures --html`,
// `samp view` and `samp eval --pictures` call) -----------------------------------

struct FitVisualsOptions {
  std::string output_dir;           // a `samp fit` output folder (tracks.json, meshes/, ...)
  bool pictures = true;             // PNGs (FitPictureOptions) into pictures_folder
  bool html = true;                 // the viewer page into html_path
  bool only_error_surfaces = false; // pictures: only track_<id>_error.png (samp eval)
  std::string pictures_folder;      // "" = <output_dir>/pictures
  std::string html_path;            // "" = <output_dir>/index.html
  LoadFitRunOptions load;
  FitPictureOptions picture;        // its output_folder is set from pictures_folder
  FitHtmlOptions page;

  void Check() const;
};

struct FitVisualsSummary {
  int num_sequences = 0, num_tracks = 0;
  std::vector<std::string> pictures;
  std::string html;                 // the page written, "" when none
  size_t html_bytes = 0;
  double seconds = 0.0;
  std::string BriefReport() const;
};

// Reads the run once (LoadFitRun) and writes what the options ask for.
FitVisualsSummary WriteFitVisuals(const FitVisualsOptions& options);

}  // namespace samp
