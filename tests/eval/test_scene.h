// Helpers of the eval tests: a small car-like mesh and quick synthesis options.
#pragma once

#include <string>

#include "libsamp/core/mesh.h"
#include "libsamp/eval/synth.h"
#include "libsamp/model/shape_model.h"

namespace samp::test {

// A 4.2 x 1.45 x 1.7 m two-box car in the canonical frame (origin bottom centre,
// x front, y down, z left), `scale` stretches the length.
Mesh MakeBoxCar(double length = 4.2);

// Small images (400 x 120, KITTI's field of view), few frames, true-disparity noise mode;
// the scene preset as given (street = the default of `samp synth`, with one parked car).
SynthOptions QuickSynthOptions(const std::string& output_folder, uint64_t seed,
                               SynthScene scene = SynthScene::kStreet);

// A two-component shape model of box cars: mean = a 4.0 x 1.45 x 1.7 m box,
// components = length and height changes (std. dev. 0.3 m and 0.1 m).
ShapeModel MakeBoxModel();

// A fresh empty folder under the system temp directory.
std::string MakeTempFolder(const std::string& name);

}  // namespace samp::test
