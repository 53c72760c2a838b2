#include "libsamp/data/sequence.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/data/detection_files.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/kitti_text.h"
#include "libsamp/data/kitti_tracking.h"
#include "libsamp/data/sequence_layout.h"
#include "libsamp/data/sequence_option_table.h"

namespace samp {
namespace fs = std::filesystem;
namespace {

// Frame numbers of the files "<name>_<ff><extension>" in `folder`, mapped to their paths.
std::map<int, std::string> ListFrameFiles(const fs::path& folder, const std::string& name,
                                          const std::string& extension) {
  std::map<int, std::string> files;
  std::error_code error;
  if (!fs::is_directory(folder, error)) return files;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (!entry.is_regular_file()) continue;
    const int frame = SequenceLayout::FrameOfFileName(entry.path().string(), name, extension);
    if (frame < 0) continue;
    SAMP_CHECK(files.count(frame) == 0)
        << folder.string() << ": two files for frame " << frame << " ("
        << files[frame] << ", " << entry.path().string() << ")";
    files[frame] = entry.path().string();
  }
  return files;
}

bool TypeKept(const std::string& type, const SequenceOptions& options) {
  return std::any_of(options.object_types.begin(), options.object_types.end(),
                     [&](const std::string& kept) { return SameObjectType(type, kept); });
}

bool FrameInRange(int frame, const SequenceOptions& options) {
  return (options.first_frame < 0 || frame >= options.first_frame) &&
         (options.last_frame < 0 || frame <= options.last_frame);
}

}  // namespace

void SequenceOptions::Check() const {
  stereo.Check();
  road_plane.Check();
  observations.Check();
  tracker.Check();
  SequenceOptionTable().Check(*this);
  SAMP_CHECK(max_image_bytes > 0) << "SequenceOptions.max_image_bytes must be > 0, is " << max_image_bytes;
}

namespace {

// One frame per left image, with the right image of the same frame when there is one.
void AddStereoFrames(const std::map<int, std::string>& left, const std::map<int, std::string>& right,
                     SequenceFiles* files) {
  for (const auto& [frame, path] : left) {
    FrameFiles f;
    f.frame = frame;
    f.image_left = path;
    const auto it = right.find(frame);
    if (it != right.end()) f.image_right = it->second;
    files->frames.push_back(f);
  }
}

// A sequence of KITTI tracking's layout (data/kitti_tracking.h).
SequenceFiles ListKittiTrackingSequence(const std::string& directory, const KittiTrackingLayout& layout) {
  std::error_code error;
  SequenceFiles files;
  files.layout = SequenceFiles::Layout::kKittiTracking;
  files.directory = directory;
  files.name = layout.name();
  files.calibration = layout.Calibration();
  SAMP_CHECK(fs::is_regular_file(files.calibration, error))
      << "KITTI tracking sequence " << directory << ": missing " << files.calibration
      << " (P0..P3, R_rect, Tr_velo_cam, Tr_imu_velo)";
  files.oxts = layout.Oxts();
  SAMP_CHECK(fs::is_regular_file(files.oxts, error))
      << "KITTI tracking sequence " << directory << ": missing " << files.oxts << " (GPS/IMU, the ego poses)";
  std::map<int, std::string> left, right;
  for (const auto& [folder, m] : {std::pair{layout.LeftImageFolder(), &left}, std::pair{layout.RightImageFolder(), &right}}) {
    if (!fs::is_directory(folder, error)) continue;
    for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
      if (!entry.is_regular_file()) continue;
      const int frame = KittiTrackingLayout::FrameOfFileName(entry.path().string(), ".png");
      if (frame < 0) continue;
      SAMP_CHECK(m->count(frame) == 0) << folder << ": two files for frame " << frame << " ("
                                       << (*m)[frame] << ", " << entry.path().string() << ")";
      (*m)[frame] = entry.path().string();
    }
  }
  SAMP_CHECK(!left.empty()) << "KITTI tracking sequence " << directory << ": no <ffffff>.png images";
  AddStereoFrames(left, right, &files);
  return files;
}

// A sequence of KITTI stereo 2015's layout, named by its calibration file
// ROOT/calib_cam_to_cam/<seq>.txt.
SequenceFiles ListKittiStereoSequence(const std::string& calibration) {
  const fs::path root = fs::path(calibration).parent_path().parent_path();
  SequenceFiles files;
  files.layout = SequenceFiles::Layout::kKittiStereo;
  files.directory = calibration;
  files.name = fs::path(calibration).stem().string();
  files.calibration = calibration;
  const auto left = ListFrameFiles(root / SequenceLayout::kLeftImageFolder, files.name, ".png");
  const auto right = ListFrameFiles(root / SequenceLayout::kRightImageFolder, files.name, ".png");
  SAMP_CHECK(!left.empty()) << "KITTI stereo sequence " << calibration << ": no "
                            << (root / SequenceLayout::kLeftImageFolder / (files.name + "_<ff>.png")).string()
                            << " images";
  AddStereoFrames(left, right, &files);
  return files;
}

bool IsKittiStereoCalibration(const std::string& path) {
  std::error_code error;
  return fs::is_regular_file(path, error) && fs::path(path).parent_path().filename() == "calib_cam_to_cam";
}

}  // namespace

void ParseFrameRange(const std::string& range, SequenceOptions* options) {
  const size_t dash = range.find('-');
  auto number = [&](const std::string& text) {
    SAMP_CHECK(!text.empty() && text.size() <= 6 && text.find_first_not_of("0123456789") == std::string::npos)
        << "--frames '" << range << "': expected FIRST-LAST frame numbers (e.g. 100-300)";
    return std::stoi(text);
  };
  options->first_frame = number(range.substr(0, dash));
  options->last_frame = dash == std::string::npos ? options->first_frame : number(range.substr(dash + 1));
  SAMP_CHECK(options->first_frame <= options->last_frame) << "--frames '" << range << "': first after last";
}

std::vector<std::string> KittiStereoSequences(const std::string& root, const std::string& sequences) {
  std::error_code error;
  const fs::path calib = fs::path(root) / "calib_cam_to_cam";
  SAMP_CHECK(fs::is_directory(calib, error))
      << "KITTI stereo root " << root << " has no calib_cam_to_cam/ folder (P_rect_02, P_rect_03 per sequence)";
  std::vector<std::string> names;
  if (sequences == "all") {
    for (const fs::directory_entry& entry : fs::directory_iterator(calib)) {
      if (!entry.is_regular_file() || entry.path().extension() != ".txt") continue;
      const std::string name = entry.path().stem().string();
      if (!ListFrameFiles(fs::path(root) / SequenceLayout::kLeftImageFolder, name, ".png").empty()) names.push_back(name);
    }
    std::sort(names.begin(), names.end());
    SAMP_CHECK(!names.empty()) << root << ": no sequence has both calib_cam_to_cam/<seq>.txt and image_2/<seq>_<ff>.png";
  } else {
    names = kitti_text::ParseSequenceList(sequences, 6);
  }
  std::vector<std::string> files;
  for (const std::string& name : names) {
    const fs::path file = calib / (name + ".txt");
    SAMP_CHECK(fs::is_regular_file(file, error)) << "KITTI stereo root " << root << " has no sequence " << name
                                                  << " (no " << file.string() << ")";
    files.push_back(file.string());
  }
  return files;
}

SequenceFiles ListSequence(const std::string& directory) {
  KittiTrackingLayout kitti("", "");
  if (KittiTrackingLayout::FromSequenceFolder(directory, &kitti)) return ListKittiTrackingSequence(directory, kitti);
  if (IsKittiStereoCalibration(directory)) return ListKittiStereoSequence(directory);
  const fs::path root(directory);
  std::error_code error;
  SAMP_CHECK(fs::is_directory(root, error)) << "sequence directory " << directory << " does not exist";
  const fs::path calib_dir = root / SequenceLayout::kCalibrationFolder;
  SAMP_CHECK(fs::is_directory(calib_dir, error))
      << "sequence " << directory << " has no calib/ folder (calib/<seq>.txt with P2 and P3)";
  std::vector<fs::path> calib_files;
  for (const fs::directory_entry& entry : fs::directory_iterator(calib_dir))
    if (entry.is_regular_file() && entry.path().extension() == ".txt") calib_files.push_back(entry.path());
  std::sort(calib_files.begin(), calib_files.end());
  SAMP_CHECK(!calib_files.empty()) << calib_dir.string() << ": no <seq>.txt calibration file";
  fs::path calib = calib_files.front();
  if (calib_files.size() > 1) {
    const std::string wanted = fs::absolute(root).lexically_normal().filename().string();
    const auto match = std::find_if(calib_files.begin(), calib_files.end(), [&](const fs::path& p) {
      return p.stem().string() == wanted;
    });
    SAMP_CHECK(match != calib_files.end())
        << calib_dir.string() << ": " << calib_files.size()
        << " calibration files and none named after the directory: which sequence is it?";
    calib = *match;
  }
  SequenceFiles files;
  files.directory = directory;
  files.name = calib.stem().string();
  files.calibration = calib.string();
  const SequenceLayout layout(directory, files.name);
  const std::string poses = layout.Poses();
  if (fs::exists(poses, error)) files.poses = poses;

  const auto left = ListFrameFiles(layout.Folder(SequenceLayout::kLeftImageFolder), files.name, ".png");
  const auto right = ListFrameFiles(layout.Folder(SequenceLayout::kRightImageFolder), files.name, ".png");
  const auto disparity = ListFrameFiles(layout.Folder(SequenceLayout::kDisparityFolder), files.name, ".png");
  const auto detections = ListFrameFiles(layout.Folder(SequenceLayout::kDetectionsFolder), files.name, ".txt");
  const auto planes = ListFrameFiles(layout.Folder(SequenceLayout::kPlanesFolder), files.name, ".txt");
  std::set<int> numbers;
  for (const auto* m : {&left, &disparity, &detections})
    for (const auto& [frame, path] : *m) numbers.insert(frame);
  SAMP_CHECK(!numbers.empty()) << "sequence " << directory << ": no frames (no " << files.name
                               << "_<ff> files in image_2/, disparity/ or detections/)";
  auto get = [](const std::map<int, std::string>& m, int frame) {
    const auto it = m.find(frame);
    return it == m.end() ? std::string() : it->second;
  };
  for (int frame : numbers) {
    FrameFiles f;
    f.frame = frame;
    f.image_left = get(left, frame);
    f.image_right = get(right, frame);
    f.disparity = get(disparity, frame);
    f.detections = get(detections, frame);
    f.plane = get(planes, frame);
    files.frames.push_back(f);
  }
  return files;
}

SequenceReader::SequenceReader(const std::string& directory, const SequenceOptions& options)
    : options_(options) {
  options_.Check();
  files_ = ListSequence(directory);
  // The image size: from the first left image, else the first disparity map.
  int width = 1242, height = 375;
  bool size_known = false;
  for (const FrameFiles& f : files_.frames) {
    const std::string& probe = !f.image_left.empty() ? f.image_left : f.disparity;
    if (probe.empty()) continue;
    const PngHeader image = ReadPngHeader(probe);  // the size, without decoding
    SAMP_CHECK(image.width <= 1000000 && image.height <= 1000000)
        << probe << ": PNG header announces " << image.width << " x " << image.height << " pixels";
    width = int(image.width);
    height = int(image.height);
    size_known = true;
    break;
  }
  if (!size_known)
    LogInfo() << files_.name << ": no image or disparity to take the image size from, using "
              << width << "x" << height;
  // 0x0: the size is not known, the principal point is not checked against it.
  calibration_ = size_known ? ReadCalibration(files_.calibration, width, height)
                            : ReadCalibration(files_.calibration);
  if (files_.layout == SequenceFiles::Layout::kKittiTracking) {
    const KittiTrackingCalibration kitti = ReadKittiTrackingCalibration(files_.calibration);
    camera_from_label_frame_ = kitti.Camera2FromRectified0();
    const std::vector<OxtsRecord> records = ReadOxts(files_.oxts);
    const int last = files_.frames.back().frame;
    SAMP_CHECK(static_cast<int>(records.size()) > last)
        << files_.oxts << ":" << records.size() + 1 << ": no GPS/IMU record for frame " << records.size()
        << " (the file has " << records.size() << " lines, the sequence has frames up to " << last << ")";
    poses_ = CameraPosesFromOxts(records, kitti);
  } else if (files_.layout == SequenceFiles::Layout::kKittiStereo) {
    camera_from_label_frame_ = ReadCamera2Offset(files_.calibration);
    LogInfo() << files_.name << ": KITTI stereo 2015 has no ego poses, assuming a static camera";
  } else if (!files_.poses.empty()) {
    poses_ = ReadPoses(files_.poses);
    const int last = files_.frames.back().frame;
    SAMP_CHECK(static_cast<int>(poses_.size()) > last)
        << files_.poses << ": " << poses_.size() << " poses (frames 0.." << poses_.size() - 1
        << "), but the sequence has frame " << last;
  } else if (files_.layout == SequenceFiles::Layout::kSamp) {
    LogInfo() << files_.name << ": no poses/" << files_.name
              << ".txt, assuming a static camera (identity ego poses)";
  }
  ResolveDetections();
}

void SequenceReader::ResolveDetections() {
  std::error_code error;
  const std::string& path = options_.detections_path;
  const DetectionFormat format = ParseDetectionFormat(options_.detection_format);
  if (path.empty()) {
    if (files_.layout == SequenceFiles::Layout::kSamp)
      detections_source_ = (fs::path(files_.directory) / SequenceLayout::kDetectionsFolder).string();
    return;  // KITTI tracking: none (an error when they are read)
  }
  std::string file = path;
  if (fs::is_directory(path, error)) {
    file = (fs::path(path) / (files_.name + ".txt")).string();
    if (format == DetectionFormat::kKittiObject || !fs::is_regular_file(file, error)) {
      // Per-frame KITTI object files <folder>/<seq>_<ff>.txt.
      SAMP_CHECK(format == DetectionFormat::kAuto || format == DetectionFormat::kKittiObject)
          << "detections folder " << path << " has no " << files_.name << ".txt for --detection-format "
          << options_.detection_format;
      for (FrameFiles& f : files_.frames) {
        const std::string frame_file = (fs::path(path) / SequenceLayout::FrameFileName(files_.name, f.frame, ".txt")).string();
        f.detections = fs::is_regular_file(frame_file, error) ? frame_file : std::string();
      }
      detections_source_ = path;
      return;
    }
  }
  SAMP_CHECK(fs::is_regular_file(file, error)) << "detections " << path << " do not exist";
  detections_source_ = file;
  detections_from_file_ = true;
  std::set<int> frames;
  for (const FrameFiles& f : files_.frames) frames.insert(f.frame);
  for (ObjectLabel& label : ReadDetectionFile(file, format)) {
    SAMP_CHECK(frames.count(label.frame) > 0)
        << file << ": a detection in frame " << label.frame << ", which sequence " << files_.name
        << " does not have (frames " << *frames.begin() << ".." << *frames.rbegin() << ")";
    file_detections_[label.frame].push_back(label);
  }
  LogInfo() << files_.name << ": detections from " << file;
}

Eigen::Isometry3d SequenceReader::WorldFromCamera(int frame) const {
  if (poses_.empty()) return Eigen::Isometry3d::Identity();
  SAMP_CHECK(frame >= 0 && frame < static_cast<int>(poses_.size()))
      << files_.poses << ": no pose for frame " << frame;
  return poses_[frame];
}

std::vector<ObjectLabel> SequenceReader::ReadDetections(int index) const {
  SAMP_CHECK(index >= 0 && index < num_frames()) << "SequenceReader: frame index " << index << " out of range";
  const FrameFiles& f = files_.frames[index];
  std::vector<ObjectLabel> labels;
  std::string source = f.detections;
  if (detections_from_file_) {
    const auto it = file_detections_.find(f.frame);
    if (it != file_detections_.end()) labels = it->second;
    source = detections_source_ + " (frame " + std::to_string(f.frame) + ")";
  } else {
    SAMP_CHECK(!detections_source_.empty())
        << (files_.layout == SequenceFiles::Layout::kKittiStereo ? "KITTI stereo sequence " : "KITTI tracking sequence ")
        << files_.directory << " has no detections: give a detection file or folder (samp fit --detections"
        << (files_.layout == SequenceFiles::Layout::kKittiTracking
                ? "; e.g. the ground truth, --detections " +
                      fs::path(files_.calibration).parent_path().parent_path().string() + "/label_02"
                : std::string())
        << ") or tracks (--tracks)";
    SAMP_CHECK(!f.detections.empty())
        << "sequence " << files_.directory << ": missing "
        << (options_.detections_path.empty() ? std::string("detections") : detections_source_) << "/"
        << SequenceLayout::FrameTag(files_.name, f.frame) << ".txt (an empty file means no detections)";
    labels = ReadLabels(f.detections);
  }
  std::vector<ObjectLabel> kept;
  int number = 0;
  for (ObjectLabel& label : labels) {
    ++number;
    if (!TypeKept(label.type, options_) || label.score < options_.min_detection_score) continue;
    // The tracker needs a box with a volume; say which file holds one without.
    SAMP_CHECK(label.height > 0 && label.width > 0 && label.length > 0)
        << source << ": detection " << number << " (" << label.type << ") has a zero size h w l = "
        << label.height << " " << label.width << " " << label.length << " m";
    label = MoveLabel(label, camera_from_label_frame_);
    label.frame = f.frame;
    kept.push_back(label);
  }
  return kept;
}

SequenceFrame SequenceReader::ReadFrame(int index, bool with_detections) const {
  SAMP_CHECK(index >= 0 && index < num_frames()) << "SequenceReader: frame index " << index << " out of range";
  const FrameFiles& f = files_.frames[index];
  const std::string tag = SequenceLayout::FrameTag(files_.name, f.frame);
  const cv::Size size(calibration_.camera.width, calibration_.camera.height);
  SequenceFrame frame;
  frame.frame = f.frame;
  frame.world_from_camera = WorldFromCamera(f.frame);
  if (with_detections) frame.detections = ReadDetections(index);

  if (!f.disparity.empty()) {
    frame.disparity_px = ReadDisparity(f.disparity, size, options_.max_image_bytes);
  } else {
    SAMP_CHECK(!f.image_left.empty() && !f.image_right.empty())
        << "sequence " << files_.directory << ": frame " << tag << " has "
        << (files_.layout == SequenceFiles::Layout::kKittiTracking
                ? "no image_03 image (" + KittiTrackingLayout(fs::path(files_.calibration).parent_path().parent_path().string(), files_.name).RightImage(f.frame) + ") to compute the disparity with"
                : "no disparity/" + tag + ".png and no image_2/image_3 pair to compute it from");
    const cv::Mat left = ReadImage(f.image_left, cv::IMREAD_GRAYSCALE, "left image", options_.max_image_bytes);
    const cv::Mat right = ReadImage(f.image_right, cv::IMREAD_GRAYSCALE, "right image", options_.max_image_bytes);
    SAMP_CHECK(left.size() == size && right.size() == size)
        << "frame " << tag << ": image_2 is " << left.cols << "x" << left.rows << ", image_3 is "
        << right.cols << "x" << right.rows << ", expected " << size.width << "x" << size.height;
    frame.disparity_px = ComputeDisparity(left, right, options_.stereo);
    frame.disparity_computed = true;
    frame.notes.push_back(tag + ": no disparity file, computed with StereoSGBM");
  }

  if (!f.plane.empty()) {
    frame.plane_in_camera = ReadPlane(f.plane);
  } else {
    RoadPlaneOptions plane_options = options_.road_plane;
    plane_options.seed = options_.road_plane.seed + static_cast<std::uint64_t>(f.frame);
    RoadPlaneSummary plane_summary;
    const std::vector<StereoPoint> points =
        DisparityToPoints(frame.disparity_px, calibration_, 1.0, /*stride=*/2,
                          cv::Rect(0, size.height / 3, size.width, size.height - size.height / 3));
    frame.plane_in_camera = EstimateRoadPlane(points, plane_options, &plane_summary);
    frame.plane_estimated = true;
    std::ostringstream note;
    if (plane_summary.success) {
      note << tag << ": no plane file, estimated the road plane by RANSAC (" << plane_summary.BriefReport()
           << "; camera height " << frame.plane_in_camera[3] << " m)";
    } else {
      frame.plane_estimation_failed = true;
      note << tag << ": no plane file and " << plane_summary.BriefReport()
           << "; using the default plane 1.65 m below the camera";
    }
    frame.notes.push_back(note.str());
  }
  for (const std::string& note : frame.notes) {
    if (frame.plane_estimation_failed && note.find("failed") != std::string::npos) {
      LogWarning() << note;
    } else {
      LogInfo() << note;
    }
  }
  return frame;
}

void LabelsInLayoutFrame(const SequenceSummary& summary, std::vector<ObjectLabel>* labels) {
  for (ObjectLabel& label : *labels) label = MoveLabel(label, summary.label_frame_offset);
}

std::string SequenceSummary::BriefReport() const {
  std::ostringstream s;
  s << "sequence " << name << ": " << num_frames << " frames, " << num_tracks << " tracks, "
    << num_track_frames << " track frames (" << num_track_frames_without_points
    << " without points), " << num_candidate_points << " candidate points; poses "
    << (poses_from_file ? "from file" : "static camera") << "; tracks "
    << (tracks_from_labels ? "from labels" : "linked") << " (" << tracking.BriefReport() << ")";
  if (frames_with_computed_disparity > 0) s << "; SGBM disparity in " << frames_with_computed_disparity << " frames";
  if (frames_with_estimated_plane > 0)
    s << "; RANSAC plane in " << frames_with_estimated_plane << " frames ("
      << frames_plane_estimation_failed << " failed, default used)";
  return s.str();
}

namespace {

// The detections linked into tracks: by the tracker (options.tracker, its
// min_track_length capped at the number of frames) or read from
// options.tracking_labels_path. `indices` are the reader's frame indices in
// the range, index_of_frame their inverse.
std::vector<LinkedTrack> LinkSequenceTracks(const std::string& directory, const SequenceReader& reader,
                                            const SequenceOptions& options, const std::vector<int>& indices,
                                            const std::map<int, int>& index_of_frame, SequenceSummary* result) {
  const SequenceFiles& files = reader.files();
  // A track cannot be longer than the sequence: in a sequence of fewer frames
  // than min_track_length (e.g. one KITTI stereo frame) tracks of every frame
  // are kept.
  TrackerOptions tracker = options.tracker;
  if (tracker.min_track_length > result->num_frames) {
    tracker.min_track_length = result->num_frames;
    result->messages.push_back(files.name + ": " + std::to_string(result->num_frames) +
                               " frame(s), fewer than min_track_length " +
                               std::to_string(options.tracker.min_track_length) +
                               ": tracks of " + std::to_string(result->num_frames) + " frame(s) kept");
  }
  if (options.tracking_labels_path.empty()) {
    std::vector<FrameDetections> detections;
    for (int i : indices) {
      FrameDetections fd;
      fd.frame = files.frames[i].frame;
      fd.world_from_camera = reader.WorldFromCamera(fd.frame);
      fd.detections = reader.ReadDetections(i);
      detections.push_back(std::move(fd));
    }
    return LinkDetections(detections, tracker, &result->tracking);
  }
  std::vector<ObjectLabel> labels;
  for (const ObjectLabel& label : ReadTrackingLabels(options.tracking_labels_path)) {
    if (!TypeKept(label.type, options) || label.score < options.min_detection_score) continue;
    if (!FrameInRange(label.frame, options)) continue;
    SAMP_CHECK(index_of_frame.count(label.frame) > 0)
        << options.tracking_labels_path << ": track " << label.track_id << " has a label in frame "
        << label.frame << ", which sequence " << directory << " does not have";
    labels.push_back(MoveLabel(label, -reader.label_frame_offset()));
  }
  result->tracks_from_labels = true;
  return TracksFromLabels(labels, tracker.min_track_length, &result->tracking);
}

// The track frames of every linked track with their candidate points
// (ExtractObservations): frames are read in parallel, each task filling only
// its own TrackFrame slots; a point nearer to another detection of its frame
// is that one's (ObservationOptions::nearest_box_claims). Returns the frames
// read (disparity released) for the summary.
std::vector<SequenceFrame> FillTrackFrames(const SequenceReader& reader, const SequenceOptions& options,
                                           const std::vector<LinkedTrack>& linked,
                                           const std::map<int, int>& index_of_frame, std::vector<Track>* tracks) {
  // Which (track, detection) pairs each frame serves.
  std::map<int, std::vector<std::pair<int, int>>> members_of_frame;  // frame -> (track, k)
  for (int t = 0; t < static_cast<int>(linked.size()); ++t)
    for (int k = 0; k < static_cast<int>(linked[t].detections.size()); ++k)
      members_of_frame[linked[t].detections[k].frame].push_back({t, k});
  std::vector<int> work_frames;
  for (const auto& [frame, members] : members_of_frame) work_frames.push_back(frame);

  std::vector<SequenceFrame> read(work_frames.size());
  tbb::parallel_for(size_t(0), work_frames.size(), [&](size_t w) {
    const int frame_number = work_frames[w];
    SequenceFrame frame = reader.ReadFrame(index_of_frame.at(frame_number), /*with_detections=*/false);
    const Eigen::Vector4d plane_in_world = TransformPlane(frame.plane_in_camera, frame.world_from_camera);
    const std::vector<std::pair<int, int>>& members = members_of_frame.at(frame_number);
    for (const auto& [t, k] : members) {
      std::vector<ObjectLabel> rivals;  // the frame's other detections
      for (const auto& [t2, k2] : members)
        if (t2 != t) rivals.push_back(linked[t2].detections[k2]);
      TrackFrame& tf = (*tracks)[t].frames[k];
      tf.frame = frame_number;
      tf.time = frame_number / options.tracker.frame_rate_hz;
      tf.detection = linked[t].detections[k];
      tf.detection_covariance = DetectionCovariance(tf.detection.position, options.tracker);
      tf.world_from_camera = frame.world_from_camera;
      tf.ground_plane_in_world = plane_in_world;
      ExtractObservations(frame.disparity_px, reader.calibration(), options.observations, linked[t].id, &tf,
                          rivals);
    }
    frame.disparity_px.release();
    read[w] = std::move(frame);
  });
  return read;
}

// The sequence's name, layout and pose source in the summary, with a
// message for each substitute (no ego poses, detections from another source).
void DescribeSequence(const SequenceReader& reader, const SequenceOptions& options, SequenceSummary* result) {
  const SequenceFiles& files = reader.files();
  result->name = files.name;
  result->poses_from_file = reader.has_poses();
  result->label_frame_offset = reader.label_frame_offset();
  if (files.layout == SequenceFiles::Layout::kKittiStereo) {
    result->layout = "kitti-stereo";
    result->messages.push_back(files.name + ": KITTI stereo 2015 layout (" + files.calibration +
                               "), no ego poses: static camera assumed");
  }
  if (files.layout == SequenceFiles::Layout::kKittiTracking) {
    result->layout = "kitti-tracking";
    result->messages.push_back(files.name + ": KITTI tracking layout, ego poses from " + files.oxts +
                               ", detections from " +
                               (options.tracking_labels_path.empty() ? reader.detections_source() : "--tracks"));
  }
  if (!reader.has_poses() && files.layout == SequenceFiles::Layout::kSamp)
    result->messages.push_back(files.name + ": no poses file, static camera assumed");
}

// The reader's frames within options' range.
struct FramesInRange {
  std::vector<int> indices;           // the reader's frame indices
  std::map<int, int> index_of_frame;  // frame number -> index
};

// Throws samp::Error when the range holds no frame.
FramesInRange SelectFrames(const std::string& directory, const SequenceReader& reader,
                           const SequenceOptions& options) {
  const SequenceFiles& files = reader.files();
  FramesInRange range;
  for (int i = 0; i < reader.num_frames(); ++i) {
    if (!FrameInRange(files.frames[i].frame, options)) continue;
    range.indices.push_back(i);
    range.index_of_frame[files.frames[i].frame] = i;
  }
  SAMP_CHECK(!range.indices.empty()) << "sequence " << directory << ": no frames in the range ["
                                     << options.first_frame << ", " << options.last_frame << "]";
  return range;
}

// Gaps in the frame numbering (frames without any file): said once per gap,
// in the messages (tracks.json) and as a warning.
void ReportFrameGaps(const SequenceFiles& files, const std::vector<int>& indices, SequenceSummary* result) {
  for (size_t k = 1; k < indices.size(); ++k) {
    const int before = files.frames[indices[k - 1]].frame, after = files.frames[indices[k]].frame;
    if (after == before + 1) continue;
    const std::string gap = files.name + ": frame(s) " + std::to_string(before + 1) +
                            (after - 1 > before + 1 ? " to " + std::to_string(after - 1) : std::string()) +
                            " missing (no image, disparity or detection file) between frames " +
                            std::to_string(before) + " and " + std::to_string(after);
    LogWarning() << gap;
    result->messages.push_back(gap);
  }
}

// The tracking summary in the log, its warnings also in the messages.
void ReportTracking(const std::string& name, SequenceSummary* result) {
  if (result->tracking.num_short_tracks > 0) LogInfo() << name << ": " << result->tracking.BriefReport();
  for (const std::string& warning : result->tracking.warnings) {
    LogWarning() << name << ": " << warning;
    result->messages.push_back(name + ": " + warning);
  }
}

// One track per linked track, with a TrackFrame slot per detection (filled by FillTrackFrames).
std::vector<Track> EmptyTracks(const SequenceReader& reader, const std::vector<LinkedTrack>& linked) {
  std::vector<Track> tracks(linked.size());
  for (size_t t = 0; t < linked.size(); ++t) {
    tracks[t].id = linked[t].id;
    tracks[t].sequence = reader.files().name;
    tracks[t].type = linked[t].detections.front().type;
    tracks[t].calibration = reader.calibration();
    tracks[t].frames.resize(linked[t].detections.size());
  }
  return tracks;
}

// What reading the frames substituted (estimated planes, computed disparity), counted and noted.
void CountFrameSubstitutes(const std::vector<SequenceFrame>& frames, SequenceSummary* result) {
  for (const SequenceFrame& frame : frames) {
    result->frames_with_estimated_plane += frame.plane_estimated ? 1 : 0;
    result->frames_with_computed_disparity += frame.disparity_computed ? 1 : 0;
    result->frames_plane_estimation_failed += frame.plane_estimation_failed ? 1 : 0;
    result->messages.insert(result->messages.end(), frame.notes.begin(), frame.notes.end());
  }
}

// Track frames and candidate points, with a message for each track frame without points.
void CountTrackFrames(const std::string& name, const std::vector<Track>& tracks, SequenceSummary* result) {
  for (const Track& track : tracks)
    for (const TrackFrame& tf : track.frames) {
      ++result->num_track_frames;
      result->num_candidate_points += static_cast<long long>(tf.candidate_points_in_world.size());
      if (tf.candidate_points_in_world.empty()) {
        ++result->num_track_frames_without_points;
        result->messages.push_back(name + ": track " + std::to_string(track.id) + " has no stereo points in frame " +
                                   std::to_string(tf.frame));
      }
    }
  result->num_tracks = static_cast<int>(tracks.size());
}

}  // namespace

std::vector<Track> LoadSequenceTracks(const std::string& directory, const SequenceOptions& options,
                                      SequenceSummary* summary) {
  options.Check();
  const SequenceReader reader(directory, options);
  const SequenceFiles& files = reader.files();
  SequenceSummary local;
  SequenceSummary& result = summary != nullptr ? *summary : local;
  result = SequenceSummary();
  DescribeSequence(reader, options, &result);
  const FramesInRange range = SelectFrames(directory, reader, options);
  result.num_frames = static_cast<int>(range.indices.size());
  ReportFrameGaps(files, range.indices, &result);

  const auto start = std::chrono::steady_clock::now();
  const std::vector<LinkedTrack> linked =
      LinkSequenceTracks(directory, reader, options, range.indices, range.index_of_frame, &result);
  const auto linked_at = std::chrono::steady_clock::now();
  result.seconds_tracking = std::chrono::duration<double>(linked_at - start).count();
  ReportTracking(files.name, &result);
  std::vector<Track> tracks = EmptyTracks(reader, linked);
  CountFrameSubstitutes(FillTrackFrames(reader, options, linked, range.index_of_frame, &tracks), &result);
  result.seconds_frames = std::chrono::duration<double>(std::chrono::steady_clock::now() - linked_at).count();
  CountTrackFrames(files.name, tracks, &result);
  return tracks;
}

}  // namespace samp
