#include "libsamp/core/json_text.h"
#include "libsamp/pipeline/fit_config.h"

#include "libsamp/core/atomic_file.h"
#include "libsamp/pipeline/run_fit_option_table.h"

namespace samp {

void OptionFields(OptionsJson& io, RunFitOptions& o) {
  // The run's own fields (model, sequences, output_dir, ...; the table's
  // order), then the nested structs.
  RunFitOptionTable().Json(io, o);
  io.Nested("fit", o.fit);
  io.Nested("sequence", o.sequence);
  // The self-calibration's options (data/calibration_option_table.h), written when not the defaults.
  io.OptionalNested("calibration", o.calibration);
}

void WriteFitConfig(const std::string& path, const FitConfig& config) {
  nlohmann::json j = OptionsToJson(config.options);
  j["model_components"] = config.model_components;
  if (!config.detector_model.origin.empty())
    j["detector_model_used"] = DetectorModelRecordToJson(config.detector_model, path);
  WriteTextFileAtomically(path, DumpJson(j, 2) + "\n");
}

FitConfig ReadFitConfig(const std::string& path) {
  const nlohmann::json json = ReadJsonFile(path);
  const JsonFields fields(json, path);
  FitConfig config;
  OptionsFromJson(fields, &config.options);
  fields.Read("model_components", &config.model_components);
  if (fields.Has("detector_model_used"))
    config.detector_model = DetectorModelRecordFromJson(fields.Object("detector_model_used"));
  return config;
}

}  // namespace samp
