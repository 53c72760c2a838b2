// The layout of a sequence directory (docs/sequence_format.md): the one place
// where the paths below SEQ/ and SEQ/gt/ and the frame file name are written
// down. The reader (data/sequence.h), the synthetic writer (eval/synth.h) and
// the evaluation (eval/evaluation.h) all build their paths here.
//
//   SEQ/calib/<seq>.txt                  P2, P3 (data/kitti_io.h ReadCalibration)
//   SEQ/poses/<seq>.txt                  world_from_camera per frame (ReadPoses)
//   SEQ/image_2|image_3/<seq>_<ff>.png   left / right images
//   SEQ/disparity/<seq>_<ff>.png         disparity (ReadDisparity)
//   SEQ/detections/<seq>_<ff>.txt        KITTI object labels (ReadLabels)
//   SEQ/planes/<seq>_<ff>.txt            road plane (ReadPlane)
//   SEQ/gt/label_02/<seq>.txt            ground-truth tracking labels
//   SEQ/gt/depth|obj_map/<seq>_<ff>.png  ground-truth depth / object map
//   SEQ/gt/meshes/track_<id>.ply         ground-truth meshes (object frame)
//   SEQ/gt/cars.json                     the synthetic scene's description
//
// A value type; thread-safe to share.
#pragma once

#include <string>

namespace samp {

class SequenceLayout {
 public:
  // Folders below SEQ/.
  static constexpr const char* kCalibrationFolder = "calib";
  static constexpr const char* kPosesFolder = "poses";
  static constexpr const char* kLeftImageFolder = "image_2";
  static constexpr const char* kRightImageFolder = "image_3";
  static constexpr const char* kDisparityFolder = "disparity";
  static constexpr const char* kDetectionsFolder = "detections";
  static constexpr const char* kPlanesFolder = "planes";
  static constexpr const char* kGroundTruthFolder = "gt";

  // `directory` is SEQ, `name` is <seq> (the stem of calib/<seq>.txt).
  SequenceLayout(std::string directory, std::string name);

  const std::string& directory() const { return directory_; }
  const std::string& name() const { return name_; }

  // "<seq>_<ff>": the frame number with at least two digits.
  static std::string FrameTag(const std::string& name, int frame);
  // "<seq>_<ff><extension>" (extension with its dot).
  static std::string FrameFileName(const std::string& name, int frame, const std::string& extension);
  // The frame number of a file whose name is "<name>_<digits><extension>"; -1
  // when the name has another form. Throws samp::Error naming `path` when the
  // frame number has more than 6 digits.
  static int FrameOfFileName(const std::string& path, const std::string& name,
                             const std::string& extension);

  // SEQ/<folder>.
  std::string Folder(const char* folder) const;
  std::string Calibration() const;          // SEQ/calib/<seq>.txt
  std::string Poses() const;                // SEQ/poses/<seq>.txt
  std::string LeftImage(int frame) const;   // SEQ/image_2/<seq>_<ff>.png
  std::string RightImage(int frame) const;  // SEQ/image_3/<seq>_<ff>.png
  std::string Disparity(int frame) const;   // SEQ/disparity/<seq>_<ff>.png
  std::string Detections(int frame) const;  // SEQ/detections/<seq>_<ff>.txt
  std::string Plane(int frame) const;       // SEQ/planes/<seq>_<ff>.txt

  // Ground truth (written by samp synth, read by samp eval).
  std::string GroundTruthFolder() const;              // SEQ/gt
  std::string GroundTruthLabels() const;              // SEQ/gt/label_02/<seq>.txt
  std::string GroundTruthDepth(int frame) const;      // SEQ/gt/depth/<seq>_<ff>.png
  std::string GroundTruthObjectMap(int frame) const;  // SEQ/gt/obj_map/<seq>_<ff>.png
  std::string GroundTruthMesh(int track_id) const;    // SEQ/gt/meshes/track_<id>.ply
  std::string GroundTruthCars() const;                // SEQ/gt/cars.json

 private:
  std::string FrameFile(const char* folder, int frame, const char* extension) const;

  std::string directory_;
  std::string name_;
};

}  // namespace samp
