// Fuzz target: the model file loader (ShapeModel::Load: samp's bounded parse
// of the .vdb header, metadata and grid descriptors, the file checksum, the
// memory budget, then samp's own decoder of the grid payloads and the model
// checks; libFuzzer learns to rewrite the checksum, so mutants reach the decoder).
// Seeds: tests/fuzz/corpus/model_loader (small model files written by samp).
#include <cstddef>
#include <cstdint>

#include "libsamp/core/error.h"
#include "libsamp/model/shape_model.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = samp::fuzz::Folder().Write("model.vdb", data, size);
  try {
    const samp::ShapeModel model = samp::ShapeModel::Load(path);
    model.Check();
  } catch (const samp::Error&) {
  }
  return 0;
}
