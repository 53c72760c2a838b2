// `samp synth`: CAD cars -> synthetic KITTI-like stereo sequences with ground truth.
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "libsamp/core/log.h"
#include "libsamp/synth/synth.h"
#include "libsamp/synth/synth_option_table.h"
#include "tools/samp/commands.h"
#include "tools/samp/option_cli.h"

namespace samp::tools {

void RegisterSynthCommand(CLI::App* app) {
  struct Args {
    SynthOptions options;  // what the command line gives (on the street preset's defaults)
    SynthCarSource cars;
    std::string preset = "street";
    std::string detector_profile;
  };
  auto args = std::make_shared<Args>();
  SynthCarSource& c = args->cars;
  CLI::App* command = app->add_subcommand(
      "synth",
      "Synthesize KITTI-like stereo sequences of CAD cars with ground truth (docs/synthetic.md).\n"
      "Default: realistic streets (lanes, kerbs, facades, clutter, parked rows, traffic, paint with\n"
      "reflections, shadows, ego sway) and a stereo 3D detector's errors; --preset clean gives the\n"
      "first benchmark's clean scenes. Writes OUT/<seq>/ in the layout `samp fit` reads (calib,\n"
      "image_2, image_3, disparity, detections, planes, poses) plus OUT/<seq>/gt/ (label_02, depth,\n"
      "obj_map, meshes, cars.json). Same options and seed give the same files.");
  command->add_option("-o,--out", args->options.output_folder, "Output folder (one sub-folder per sequence)")
      ->required();
  command->add_option("--preset", args->preset,
                      "Scene preset: 'street' (realistic, the default) or 'clean' (the first benchmark's "
                      "scenes: plain paint, no clutter, white detection noise); options given explicitly "
                      "override the preset")
      ->capture_default_str()
      ->check(CLI::IsMember({"street", "clean"}));
  command->add_option("--cad", c.cad_folder, "Folder searched recursively for CAD car files")
      ->check(CLI::ExistingDirectory);
  command->add_option("--manifest", c.manifest_path,
                      "Training manifest (JSON) for canonicalisation (docs/canonical_frame.md)")
      ->check(CLI::ExistingFile);
  command->add_option("--car", c.only,
                      "Use only this car (manifest name or file stem); repeatable. Cars marked skip "
                      "in the manifest are used when named here (held-out evaluation cars)");
  command->add_option("--car-mesh", c.canonical_meshes,
                      "A mesh already in the canonical object frame (origin bottom centre, x front, "
                      "y down, z left, metres); repeatable")
      ->check(CLI::ExistingFile);
  command
      ->add_option("--detector-profile", args->detector_profile,
                   "Detections: a named detector (replaces the preset's; --det-* options given explicitly "
                   "override its fields): default (the street preset's stereo detector), lidar (position, size "
                   "and yaw sigmas x 0.25), stereo-x2 (x 2), size-x3 (box size sigmas x 3), kitti-boxes (width "
                   "0.25 m narrower, 0.2 m nearer along the ray), flips (8 % one-frame flips)")
      ->check(CLI::IsMember(DetectorProfileNames()))
      ->group("Detector model (DetectorModelOptions; docs/synthetic.md, \"Detector model\")");
  // Every field of SynthOptions with its street and detector from the table
  // (synth/synth_option_table.h), in three groups.
  std::vector<OptionBinding> scene, street, detector;
  for (OptionBinding& b : SynthOptionTable().Bind(&args->options)) {
    const std::string& name = b.info.name;
    (name.rfind("street.", 0) == 0 ? street : name.rfind("detector.", 0) == 0 ? detector : scene).push_back(b);
  }
  AddTableOptions(command, scene, "", "Scene (SynthOptions; docs/synthetic.md, \"Options\")");
  AddTableOptions(command, street, "", "Street layout (StreetOptions; docs/synthetic.md, \"Street\")");
  AddTableOptions(command, detector, "",
                  "Detector model (DetectorModelOptions; docs/synthetic.md, \"Detector model\")");
  AddHelpOptions(command, {{"markdown", SynthOptionTable().Describe(), ""}});
  AddCommonOptions(command);
  command->callback([args, command] {
    // The preset's defaults, then the options given on the command line over them.
    SynthOptions options = args->preset == "clean" ? SynthOptions::Clean() : SynthOptions();
    if (!args->detector_profile.empty()) options.detector = DetectorProfile(args->detector_profile);
    for (const OptionInfo& info : SynthOptionTable().Describe()) {
      if (!info.internal && command->count(CommandLineName(info.flag, "")) > 0) {
        SynthOptionTable().Copy(info.name, args->options, &options);
      }
    }
    options.output_folder = args->options.output_folder;
    options.show_progress = GetLogLevel() <= LogLevel::kInfo;
    const std::vector<SynthCar> cars = LoadSynthCars(args->cars);
    const SynthSummary summary = SynthesizeSequences(options, cars);
    std::cout << summary.BriefReport() << "\nwrote " << options.output_folder << std::endl;
  });
}

}  // namespace samp::tools
