// A sequence directory (layout in docs/sequence_format.md) and the tracks the
// fitter gets from it:
//   SEQ/calib/<seq>.txt, SEQ/image_2|image_3|disparity/<seq>_<ff>.png,
//   SEQ/detections|planes/<seq>_<ff>.txt, SEQ/poses/<seq>.txt
// or a sequence of KITTI tracking's own layout, named by its left image folder
// ROOT/image_02/<seq> (data/kitti_tracking.h: images, calib with P0..P3,
// R_rect, Tr_velo_cam, Tr_imu_velo, ego poses from oxts/<seq>.txt; its
// detections come from SequenceOptions::detections_path).
// Missing poses/ = static camera (identity), missing planes/<file> = RANSAC
// road plane from the stereo points, missing disparity/<file> = StereoSGBM from
// image_2/image_3; each substitution is logged and counted in the summary.
// Everything else missing or malformed throws samp::Error naming the file.
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libsamp/data/kitti_io.h"
#include "libsamp/data/observations.h"
#include "libsamp/data/road_plane.h"
#include "libsamp/data/stereo.h"
#include "libsamp/data/track.h"
#include "libsamp/data/tracking.h"

namespace samp {

struct SequenceOptions {
  StereoOptions stereo;            // when disparity/<file> is missing
  RoadPlaneOptions road_plane;     // when planes/<file> is missing
  ObservationOptions observations;
  TrackerOptions tracker;
  // Empty: link detections/ into tracks (tracking-by-detection). Otherwise a
  // KITTI tracking label file (frame track_id type ...) giving the tracks;
  // detections/ is then not read.
  std::string tracking_labels_path;
  // Detections instead of the layout's (samp: SEQ/detections/<seq>_<ff>.txt;
  // KITTI tracking has none and needs this). A file: the sequence's
  // detections (kitti-tracking or ab3dmot lines, data/detection_files.h). A
  // folder: <folder>/<seq>.txt when it exists (idem), else KITTI object files
  // <folder>/<seq>_<ff>.txt, one per frame.
  std::string detections_path;
  // Format of detections_path: auto (from the first line), kitti-object,
  // kitti-tracking, ab3dmot.
  std::string detection_format = "auto";
  // Object types kept (case-insensitive); others are ignored.
  std::vector<std::string> object_types = {"Car"};
  // Detections with a lower score are ignored.
  double min_detection_score = -1e300;
  // Only frames in [first_frame, last_frame] (-1 = unbounded).
  int first_frame = -1;
  int last_frame = -1;
  // Memory budget of one decoded image or disparity map, bytes: a PNG whose
  // header announces more is refused before decoding (data/kitti_io.h
  // ReadImage). Not written to config.json.
  int64_t max_image_bytes = kDefaultMaxImageBytes;

  void Check() const;  // throws samp::Error naming the field
};

// Paths of one frame; empty when the file does not exist.
struct FrameFiles {
  int frame = 0;
  std::string image_left, image_right, disparity, detections, plane;
};

// What a sequence directory contains (nothing read yet but the listing).
struct SequenceFiles {
  enum class Layout { kSamp, kKittiTracking, kKittiStereo };
  Layout layout = Layout::kSamp;
  std::string directory;
  std::string name;         // <seq>
  std::string calibration;  // calib/<seq>.txt
  std::string poses;        // poses/<seq>.txt, empty when absent
  std::string oxts;         // KITTI tracking: ROOT/oxts/<seq>.txt (required there)
  std::vector<FrameFiles> frames;  // increasing frame numbers
};

// Lists `directory`. <seq> is the stem of the single calib/*.txt file (or the
// one equal to the directory name). Frames are the <ff> of every
// <seq>_<ff>.{txt,png} in image_2, disparity and detections. Throws when the
// directory or calib file is missing or no frame is found.
// A folder ROOT/image_02/<seq> without calib/ is a KITTI tracking sequence
// (KittiTrackingLayout::FromSequenceFolder): its frames are the <ffffff>.png
// of that folder, its calibration ROOT/calib/<seq>.txt and its ego poses
// ROOT/oxts/<seq>.txt (both required).
// A file ROOT/calib_cam_to_cam/<seq>.txt is a sequence of KITTI stereo 2015's
// (multiview) layout: frames <seq>_<ff>.png in ROOT/image_2 and ROOT/image_3
// (00..20 in the multiview set), P_rect_02 and P_rect_03 from that file, no
// ego poses (static camera), labels in rectified camera 0 as KITTI tracking's.
SequenceFiles ListSequence(const std::string& directory);
// The calibration files ROOT/calib_cam_to_cam/<seq>.txt of `sequences` ("all":
// every one that has ROOT/image_2/<seq>_*.png, sorted; or a comma-separated
// list, numbers padded to six digits: "46" -> "000046"); throws naming what
// is missing.
std::vector<std::string> KittiStereoSequences(const std::string& root, const std::string& sequences);
// "FIRST-LAST" (or "FIRST") frame numbers, as `samp fit --frames` and
// `samp.batch fit --frames` take them, into options->first_frame and
// last_frame. Throws samp::Error quoting the text when it is not that.
void ParseFrameRange(const std::string& range, SequenceOptions* options);

// One frame, read.
struct SequenceFrame {
  int frame = 0;
  Eigen::Isometry3d world_from_camera = Eigen::Isometry3d::Identity();
  Eigen::Vector4d plane_in_camera = Eigen::Vector4d(0, -1, 0, 1.65);
  bool plane_estimated = false;      // RANSAC, no planes/ file
  bool disparity_computed = false;   // SGBM, no disparity/ file
  bool plane_estimation_failed = false;  // RANSAC failed: KITTI default plane used
  std::vector<std::string> notes;    // each substitution made, one line each (also logged)
  cv::Mat disparity_px;              // CV_32FC1, 0 = invalid
  std::vector<ObjectLabel> detections;  // filtered by type and score; empty with tracking labels
};

// Reads a sequence frame by frame. Construction reads the listing,
// calibration and poses. Not thread-safe for one instance; separate instances
// are independent.
class SequenceReader {
 public:
  SequenceReader(const std::string& directory, const SequenceOptions& options);

  const SequenceFiles& files() const { return files_; }
  const StereoCalibration& calibration() const { return calibration_; }
  bool has_poses() const { return !poses_.empty(); }
  int num_frames() const { return static_cast<int>(files_.frames.size()); }
  // Ego pose of frame number `frame` (identity without poses/).
  Eigen::Isometry3d WorldFromCamera(int frame) const;
  // Position in the layout's label frame = position in the camera + this
  // (KITTI tracking: rectified camera 0 = camera 2 - t2; samp's layout: 0).
  // Labels read from the layout's files are moved by its negative.
  Eigen::Vector3d label_frame_offset() const { return -camera_from_label_frame_; }
  // Where the detections come from (a folder of per-frame files or one file).
  const std::string& detections_source() const { return detections_source_; }

  // Detections of the frame at `index` (0..num_frames-1), filtered.
  std::vector<ObjectLabel> ReadDetections(int index) const;
  // Disparity, plane, pose and detections (when with_detections) of frame `index`.
  SequenceFrame ReadFrame(int index, bool with_detections = true) const;

 private:
  void ResolveDetections();  // the constructor's last step

  SequenceOptions options_;
  SequenceFiles files_;
  StereoCalibration calibration_;
  std::vector<Eigen::Isometry3d> poses_;
  Eigen::Vector3d camera_from_label_frame_ = Eigen::Vector3d::Zero();
  std::string detections_source_;
  // A per-sequence detection file, read once: frame -> its detections (unfiltered).
  bool detections_from_file_ = false;
  std::map<int, std::vector<ObjectLabel>> file_detections_;
};

struct SequenceSummary {
  std::string name;
  int num_frames = 0;
  bool poses_from_file = false;
  bool tracks_from_labels = false;
  std::string layout = "samp";  // "samp", "kitti-tracking" or "kitti-stereo"
  // SequenceReader::label_frame_offset: written labels are moved by it
  // (LabelsInLayoutFrame).
  Eigen::Vector3d label_frame_offset = Eigen::Vector3d::Zero();
  int frames_with_estimated_plane = 0;
  int frames_with_computed_disparity = 0;
  int frames_plane_estimation_failed = 0;  // default plane used
  TrackingSummary tracking;
  int num_tracks = 0;
  int num_track_frames = 0;
  int num_track_frames_without_points = 0;
  long long num_candidate_points = 0;
  std::vector<std::string> messages;  // every substitution/fallback, one line each
  // Wall time of the two stages, s (not in BriefReport, which tracks.json
  // records): linking the detections into tracks; reading the track frames
  // (images, disparity or SGBM, ground plane, candidate points).
  double seconds_tracking = 0.0;
  double seconds_frames = 0.0;
  std::string BriefReport() const;
};

// Reads the sequence, links tracks and fills every TrackFrame (detection,
// time = frame / frame_rate, ego pose, ground plane in world, candidate
// points). Tracks are ordered by id; frames by number. A TrackFrame is
// produced only for frames with a detection (gaps are possible). Throws
// samp::Error on bad input, naming the file.
// `labels` (camera frame, as the fitter gives them) in the label frame of the
// sequence's layout: moved by summary.label_frame_offset with alpha
// recomputed (data/kitti_tracking.h MoveLabel); unchanged for samp's layout.
void LabelsInLayoutFrame(const SequenceSummary& summary, std::vector<ObjectLabel>* labels);

std::vector<Track> LoadSequenceTracks(const std::string& directory, const SequenceOptions& options,
                                      SequenceSummary* summary = nullptr);

}  // namespace samp
