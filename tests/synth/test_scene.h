// Helpers of the synth, eval, pipeline and tools tests: small car-like meshes,
// quick synthesis options and a scene of synthetic sequences.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "libsamp/core/mesh.h"
#include "libsamp/synth/synth.h"
#include "libsamp/model/shape_model.h"

namespace samp::test {

// A 4.2 x 1.45 x 1.7 m two-box car in the canonical frame (origin bottom centre,
// x front, y down, z left), `scale` stretches the length.
Mesh MakeBoxCar(double length = 4.2);
// Two box cars of 4.2 m and 3.8 m, "boxcar_a" and "boxcar_b".
std::vector<SynthCar> TwoBoxCars();

// Small images (400 x 120, KITTI's field of view), few frames, true-disparity noise mode;
// the scene preset as given (street = the default of `samp synth`, with one parked car).
SynthOptions QuickSynthOptions(const std::string& output_folder, uint64_t seed,
                               SynthScene scene = SynthScene::kStreet);

// A two-component shape model of box cars: mean = a 4.0 x 1.45 x 1.7 m box,
// components = length and height changes (std. dev. 0.3 m and 0.1 m).
ShapeModel MakeBoxModel();

// A fresh empty folder under the system temp directory.
std::string MakeTempFolder(const std::string& name);

// The bytes of a file ("" when it cannot be read).
std::string ReadText(const std::string& path);

// `num_sequences` sequences of `num_frames` frames of the clean preset (box
// cars, no flipped detections; QuickSynthOptions with `seed`) in a fresh temp
// folder named after `name`, with the box model beside them. The destructor
// removes the folder when every test of the binary passed (a failure leaves
// it to look at). Not copyable: make one static instance per test binary.
struct BoxCarScene {
  BoxCarScene(const std::string& name, uint64_t seed, int num_sequences, int num_frames);
  ~BoxCarScene();
  BoxCarScene(const BoxCarScene&) = delete;
  BoxCarScene& operator=(const BoxCarScene&) = delete;

  // A fresh empty folder ROOT/name for one test (an earlier one is removed).
  std::string Folder(const std::string& name) const;

  std::string root;
  std::vector<std::string> sequences, names;  // each sequence's folder and its <seq>
  std::string model;                          // MakeBoxModel() as ROOT/box_model.vdb
};

}  // namespace samp::test
