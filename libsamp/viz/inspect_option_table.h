// The option tables of inspecting a model file (core/option_table.h): every
// field of EigenShapeMeshOptions, EncodeOptions and PictureOptions, and what
// `samp inspect` asks for (InspectOptions), declared once with their
// command-line names, help and rules. They drive the three structs' Check(),
// InspectOptions::Check(), `samp inspect`'s options and their lists in
// docs/inspect.md (`samp inspect --help-options markdown`, `meshes-markdown`,
// `encode-markdown`, `pictures-markdown`). Nothing stores these options.
#pragma once

#include <string>

#include "libsamp/core/option_table.h"
#include "libsamp/viz/inspect.h"

namespace samp {

// What `samp inspect MODEL` does besides printing the model's summary: each
// part runs when its folder or file is given (the folders and the manifest
// go into the part's options; --components and --format are shared).
struct InspectOptions {
  std::string model_path;       // the model file
  std::string meshes_folder;    // eigen-shape meshes ("" = none)
  std::string encode_input;     // a CAD file, SDF file or folder to project ("" = none)
  std::string encode_folder;    // with encode_input: meshes and encode.csv ("" = none)
  std::string pictures_folder;  // PNG pictures ("" = none)
  std::string manifest_path;    // canonicalisation of CAD files ("" = none)
  std::string html_path;        // the eigen-shape slider page ("" = none)
  // The parts' options (their own tables; the folders above go into them).
  EigenShapeMeshOptions meshes;
  EncodeOptions encode;
  PictureOptions pictures;

  // Throws samp::Error naming the field and the rule it broke (the fields
  // above; each part checks its options when it runs).
  void Check() const;
};

// Built once; the same table for every call.
const OptionTable<EigenShapeMeshOptions>& EigenShapeMeshOptionTable();
const OptionTable<EncodeOptions>& EncodeOptionTable();
const OptionTable<PictureOptions>& PictureOptionTable();
// InspectOptions' own fields.
const OptionTable<InspectOptions>& InspectOptionTable();

}  // namespace samp
