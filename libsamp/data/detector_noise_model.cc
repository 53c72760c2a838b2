// DetectorNoiseModel: its derived figures, its one-line report and its file,
// the samp-detector-model JSON (docs/detector_calibration.md, "The noise model"):
// this file is the format's one owner.
#include "libsamp/data/detector_noise.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/json_fields.h"
#include "libsamp/core/json_text.h"

namespace samp {
namespace {

constexpr const char* kFormat = "samp-detector-model";
constexpr const char* kDimensionNames[3] = {"height", "width", "length"};

void CheckModel(const DetectorNoiseModel& m, const std::string& where) {
  auto positive = [&](double v, const char* key) {
    SAMP_CHECK(std::isfinite(v) && v > 0) << where << ": '" << key << "' must be > 0, is " << v;
  };
  auto non_negative = [&](double v, const char* key) {
    SAMP_CHECK(std::isfinite(v) && v >= 0) << where << ": '" << key << "' must be >= 0, is " << v;
  };
  auto share = [&](double v, const char* key) {
    SAMP_CHECK(std::isfinite(v) && v >= 0 && v <= 1) << where << ": '" << key << "' must be in [0, 1], is " << v;
  };
  positive(m.along_sigma_a, "along_sigma_a");
  non_negative(m.along_sigma_b, "along_sigma_b");
  positive(m.across_sigma_a, "across_sigma_a");
  non_negative(m.across_sigma_b, "across_sigma_b");
  positive(m.vertical_sigma_a, "vertical_sigma_a");
  non_negative(m.vertical_sigma_b, "vertical_sigma_b");
  for (int i = 0; i < 3; ++i) {
    positive(m.size_sigma[i], "size.sigma");
    SAMP_CHECK(std::isfinite(m.size_bias[i])) << where << ": 'size.bias' must be finite";
  }
  SAMP_CHECK(std::isfinite(m.along_bias)) << where << ": 'along_bias' must be finite";
  positive(m.yaw_sigma_deg, "yaw_sigma_deg");
  share(m.flip_rate, "flip_rate");
  share(m.miss_rate, "miss_rate");
  non_negative(m.false_positives_per_frame, "false_positives_per_frame");
  SAMP_CHECK(m.num_dont_care_ignored >= 0)
      << where << ": 'samples.dont_care_ignored' must be >= 0, is " << m.num_dont_care_ignored;
}

}  // namespace

double DetectorNoiseModel::MeanSizeSigma() const {
  return std::sqrt((size_sigma[0] * size_sigma[0] + size_sigma[1] * size_sigma[1] + size_sigma[2] * size_sigma[2]) /
                   3.0);
}

double DetectorNoiseModel::CorrelationFrames() const {
  double mean = 0.0;
  for (double rho : correlation) mean += rho / 7.0;
  return mean > 1e-3 ? -1.0 / std::log(mean) : 0.0;
}

void DetectorNoiseModel::ApplyTo(TrackerOptions* t) const {
  t->along_sigma_a = along_sigma_a, t->along_sigma_b = along_sigma_b, t->along_sigma_c = 0.0;
  t->across_sigma_a = across_sigma_a, t->across_sigma_b = across_sigma_b;
  t->vertical_sigma_a = vertical_sigma_a, t->vertical_sigma_b = vertical_sigma_b;
  t->size_sigma = MeanSizeSigma();
  t->yaw_sigma_deg = yaw_sigma_deg;
}

std::string DetectorNoiseModel::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << source << ": along " << along_sigma_a << " + " << along_sigma_b << " d, across " << across_sigma_a << " + "
    << across_sigma_b << " d, vertical " << vertical_sigma_a << " + " << vertical_sigma_b << " d m ("
    << num_position_samples << " detections); size h/w/l " << size_sigma[0] << "/" << size_sigma[1] << "/"
    << size_sigma[2] << " m";
  if (biases_estimated)
    s << " bias " << size_bias[0] << "/" << size_bias[1] << "/" << size_bias[2] << " m, along-ray bias "
      << along_bias << " m";
  if (box_convention_estimated)
    s << " box convention (box - shape) h/w/l " << size_bias[0] << "/" << size_bias[1] << "/" << size_bias[2]
      << " m, along-ray " << along_bias << " m (" << box_convention_tracks << " cars, "
      << box_convention_detections << " detections)";
  s << " (" << num_size_samples << "); yaw " << yaw_sigma_deg << " deg (" << num_yaw_samples << ")";
  if (correlation_estimated)
    s << "; correlation between frames along/across/vertical " << correlation[0] << "/" << correlation[1] << "/"
      << correlation[2] << ", h/w/l " << correlation[3] << "/" << correlation[4] << "/" << correlation[5]
      << ", yaw " << correlation[6] << (correlation_shared ? " (one value for all cues)" : "");
  s << "; flips "
    << 100 * flip_rate << " %, misses " << 100 * miss_rate << " %, " << false_positives_per_frame
    << " false positives per frame";
  if (num_dont_care_ignored > 0) s << " (" << num_dont_care_ignored << " detections in DontCare regions ignored)";
  s << "; " << num_tracks << " tracks, " << num_frames << " frames";
  for (const std::string& n : notes) s << "; NOTE: " << n;
  return s.str();
}

// The keys of a detector model file, listed once for ToJson and
// DetectorNoiseModelFromJson; "format", "version" and the optional
// "box_convention" object are written beside them.
static void OptionFields(OptionsJson& io, DistanceBin& b) {
  io("min_distance", b.min_distance);
  io("max_distance", b.max_distance);
  io("count", b.count);
  io.Optional("tracks", b.tracks, 0);
  io.Optional("mean_distance", b.mean_distance, 0.0);
  io("along_sigma", b.along_sigma);
  io("across_sigma", b.across_sigma);
  io("vertical_sigma", b.vertical_sigma);
  io("along_bias", b.along_bias);
  io("across_bias", b.across_bias);
  io("vertical_bias", b.vertical_bias);
}

static void OptionFields(OptionsJson& io, DetectorNoiseModel& m) {
  io("source", m.source);
  io("along_sigma_a", m.along_sigma_a);
  io("along_sigma_b", m.along_sigma_b);
  io("across_sigma_a", m.across_sigma_a);
  io("across_sigma_b", m.across_sigma_b);
  io("vertical_sigma_a", m.vertical_sigma_a);
  io("vertical_sigma_b", m.vertical_sigma_b);
  io("along_bias", m.along_bias);
  io.NestedWith("size", [&m](OptionsJson& size) {
    for (int i = 0; i < 3; ++i)
      size.NestedWith(kDimensionNames[i], [&m, i](OptionsJson& d) {
        d("sigma", m.size_sigma[i]);
        d("bias", m.size_bias[i]);
      });
  });
  io("yaw_sigma_deg", m.yaw_sigma_deg);
  io("flip_rate", m.flip_rate);
  io("miss_rate", m.miss_rate);
  io("false_positives_per_frame", m.false_positives_per_frame);
  io("biases_estimated", m.biases_estimated);
  io.NestedWith("samples", [&m](OptionsJson& samples) {
    samples("position", m.num_position_samples);
    samples("size", m.num_size_samples);
    samples("yaw", m.num_yaw_samples);
    samples("tracks", m.num_tracks);
    samples("frames", m.num_frames);
    samples.Optional("dont_care_ignored", m.num_dont_care_ignored, 0);
  });
  io.Array("distance_bins", m.bins);
  io("notes", m.notes);
}

// The box convention (detected minus shape extent), present only when estimated.
static void BoxConventionFields(OptionsJson& io, DetectorNoiseModel& m) {
  io("cars", m.box_convention_tracks);
  io("detections", m.box_convention_detections);
  io.NestedWith("size_bias_error", [&m](OptionsJson& errors) {
    for (int i = 0; i < 3; ++i) errors(kDimensionNames[i], m.size_bias_error[i]);
  });
  io("along_bias_error", m.along_bias_error);
}

// The correlation between frames per cue, present only when measured.
constexpr const char* kCueNames[7] = {"along", "across", "vertical", "height", "width", "length", "yaw"};
static void CorrelationFields(OptionsJson& io, DetectorNoiseModel& m) {
  for (int c = 0; c < 7; ++c) io(kCueNames[c], m.correlation[c]);
  io("pairs", m.correlation_pairs);
  io.Optional("shared", m.correlation_shared, false);
}

std::string DetectorNoiseModel::ToJson() const {
  DetectorNoiseModel& m = const_cast<DetectorNoiseModel&>(*this);  // the writer only reads the fields
  nlohmann::json j = OptionsToJson(m);
  j["format"] = kFormat;
  j["version"] = kVersion;
  if (box_convention_estimated) {
    OptionsJson io(&j);
    io.NestedWith("box_convention", [&m](OptionsJson& box) { BoxConventionFields(box, m); });
  }
  if (correlation_estimated) {
    OptionsJson io(&j);
    io.NestedWith("correlation", [&m](OptionsJson& c) { CorrelationFields(c, m); });
  }
  return DumpJson(j, 2);
}

DetectorNoiseModel DetectorNoiseModelFromJson(const std::string& text, const std::string& source) {
  const nlohmann::json j = ParseJson(text, source);
  const JsonFields f(j, source);
  const std::string format = f.Get<std::string>("format");
  SAMP_CHECK(format == kFormat) << source << ": 'format' is '" << format << "', expected '" << kFormat << "'";
  const int version = f.Get<int>("version");
  SAMP_CHECK(version == DetectorNoiseModel::kVersion)
      << source << ": detector model version " << version << " is not supported (this samp reads version "
      << DetectorNoiseModel::kVersion << ")";
  DetectorNoiseModel m;
  OptionsFromJson(f, &m);
  for (size_t k = 0; k < m.bins.size(); ++k) {
    const DistanceBin& b = m.bins[k];
    SAMP_CHECK(b.count >= 0 && b.tracks >= 0 && b.tracks <= b.count && b.max_distance >= b.min_distance)
        << source << ": distance_bins[" << k
        << "]: a distance bin needs count >= 0, tracks in [0, count] and max_distance >= min_distance";
    SAMP_CHECK(b.mean_distance == 0.0 || (b.mean_distance >= b.min_distance && b.mean_distance <= b.max_distance))
        << source << ": distance_bins[" << k << "].mean_distance " << b.mean_distance << " is outside the bin ["
        << b.min_distance << ", " << b.max_distance << "]";
  }
  if (f.Has("box_convention")) {
    OptionsJson io(&f);
    io.NestedWith("box_convention", [&m](OptionsJson& box) { BoxConventionFields(box, m); });
    m.box_convention_estimated = true;
    SAMP_CHECK(m.box_convention_tracks >= 0 && m.box_convention_detections >= 0)
        << source << ": 'box_convention' counts must be >= 0";
    for (int i = 0; i < 3; ++i)
      SAMP_CHECK(std::isfinite(m.size_bias_error[i]) && m.size_bias_error[i] >= 0)
          << source << ": 'box_convention.size_bias_error' must be >= 0";
    SAMP_CHECK(std::isfinite(m.along_bias_error) && m.along_bias_error >= 0)
        << source << ": 'box_convention.along_bias_error' must be >= 0";
  }
  if (f.Has("correlation")) {
    OptionsJson io(&f);
    io.NestedWith("correlation", [&m](OptionsJson& c) { CorrelationFields(c, m); });
    m.correlation_estimated = true;
    for (double rho : m.correlation)
      SAMP_CHECK(std::isfinite(rho) && rho >= 0 && rho < 1) << source << ": 'correlation' values must be in [0, 1)";
  }
  CheckModel(m, source);
  return m;
}

void WriteDetectorNoiseModel(const std::string& path, const DetectorNoiseModel& model) {
  WriteTextFileAtomically(path, model.ToJson() + "\n");
}

DetectorNoiseModel ReadDetectorNoiseModel(const std::string& path) {
  const nlohmann::json j = ReadJsonFile(path);
  return DetectorNoiseModelFromJson(DumpJson(j), path);
}

}  // namespace samp
