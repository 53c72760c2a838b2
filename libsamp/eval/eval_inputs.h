// The load stage of `samp eval` (internal to libsamp/eval): one sequence's
// ground truth (labels, object-map segments, camera) and every method's labels
// of it, and the fitted surfaces of a result folder (docs/evaluation.md).
// A result folder is a `samp fit` output, read through pipeline/fit_output.h
// (FitLabelsPath, FitMeshStem, FitTracksPath); it may also hold one such
// output per sequence in <folder>/<seq>/.
#pragma once

#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <vector>

#include "libsamp/core/camera.h"
#include "libsamp/core/mesh.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/sequence_layout.h"
#include "libsamp/eval/eval_options.h"

namespace samp {
class ShapeLookup;
}

namespace samp::eval {

// The names of the two baselines among the methods.
constexpr char kStereo[] = "stereo";
constexpr char kDetections[] = "detections";

// The folder of a result that holds the fit output of sequence `seq`
// (`folder` or `folder`/<seq>), "" when it has none.
std::string ResultFolder(const std::string& folder, const std::string& seq);

// The fitted surfaces of one result folder. A single-frame fit has a shape per
// frame: when tracks.json holds per-frame shape codes, the surface of each
// frame is extracted from the model named there (pipeline/fit_output.h
// FittedSurface); otherwise the track's mesh file is used. Load() everything
// first, then Finish(); Get() is then const and thread-safe.
class ResultMeshes {
 public:
  explicit ResultMeshes(const std::string& folder);
  ~ResultMeshes();

  // Makes the surface of (seq, track, frame) available; throws when there is none.
  void Load(const std::string& seq, int track_id, int frame);
  // Extracts the pending per-frame surfaces (in parallel).
  void Finish();
  const Mesh& Get(const std::string& seq, int track_id, int frame) const;

 private:
  static std::string Key(const std::string& seq, int track_id, int frame);
  std::string folder_;
  std::string model_path_;
  std::map<std::string, Eigen::VectorXd> codes_;
  std::set<std::string> pending_codes_;
  std::map<std::string, std::string> files_;
  std::map<std::string, std::unique_ptr<Mesh>> meshes_;
  std::unique_ptr<ShapeLookup> lookup_;
};

// One sequence as the evaluation reads it.
struct SequenceInputs {
  std::string directory, seq;
  SequenceLayout layout{"", ""};
  StereoCalibration calibration;  // its camera is the image size of the ground truth
  cv::Size size;
  // The ground-truth labels by frame, and per frame the object-map segment of
  // each of them (pixels of gt/obj_map equal to track_id + 1).
  std::map<int, std::vector<ObjectLabel>> gt_by_frame;
  // Empty without ground-truth maps (has_maps false: KITTI tracking's layout).
  std::map<int, std::vector<std::vector<cv::Point>>> segments;
  bool has_maps = true;
  // Per frame and truth: evaluated (a segment of at least min_segment_pixels;
  // without maps, EvalOptions' box height, occlusion and truncation limits).
  std::map<int, std::vector<bool>> evaluated;
  // Per method: its car labels of this sequence by frame (none for the stereo
  // baseline and for a result without output for this sequence).
  std::vector<std::map<int, std::vector<ObjectLabel>>> labels;
};

// Whether `directory` is a sequence of KITTI tracking's layout (ground truth
// without maps).
bool IsKittiTrackingSequence(const std::string& directory);

// Reads sequence `directory` and the methods' labels of it. false (with a
// warning) when the sequence has no ground-truth label.
bool LoadSequenceInputs(const EvalOptions& options, const std::string& directory,
                        const std::vector<EvalMethod>& methods, SequenceInputs* inputs);

// A PNG of the ground truth with the expected pixel type and size (an empty
// size: any); throws naming the file otherwise.
cv::Mat ReadPngOfType(const std::string& path, int type, const cv::Size& size);

}  // namespace samp::eval
