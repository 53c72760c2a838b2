#include "libsamp/core/json_text.h"
#include "libsamp/pipeline/fit_config.h"

#include "libsamp/core/atomic_file.h"

namespace samp {

void OptionFields(OptionsJson& io, RunFitOptions& o) {
  io("model", o.model_path);
  io("sequences", o.sequences);
  io("tracking_labels", o.tracking_labels);
  io("output_dir", o.output_dir);
  io.Nested("fit", o.fit);
  io.Nested("sequence", o.sequence);
  io("num_threads", o.num_threads);
  io("write_meshes", o.write_meshes);
  io("link_only", o.link_only);
  // Detector calibration (issue 28; run_fit.h), written only when used.
  io.Optional("self_calibrate", o.self_calibrate, false);
  io.Optional("detector_model", o.detector_model_path, std::string());
  // The self-calibration's options (data/calibration_option_table.h), written when not the defaults.
  io.OptionalNested("calibration", o.calibration);
}

void WriteFitConfig(const std::string& path, const FitConfig& config) {
  nlohmann::json j = OptionsToJson(config.options);
  j["model_components"] = config.model_components;
  WriteTextFileAtomically(path, DumpJson(j, 2) + "\n");
}

FitConfig ReadFitConfig(const std::string& path) {
  const nlohmann::json json = ReadJsonFile(path);
  const JsonFields fields(json, path);
  FitConfig config;
  OptionsFromJson(fields, &config.options);
  fields.Read("model_components", &config.model_components);
  return config;
}

}  // namespace samp
