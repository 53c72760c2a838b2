// Fuzz target: samp's decoder of .vdb grid payloads behind a valid file
// checksum. Each input's samp_file_bytes and samp_file_checksum are
// recomputed before it is loaded (ResealVdbForTesting, when its file metadata
// parses), as somebody editing a file on purpose would do, so every mutant of
// the payload reaches the decoder instead of failing the checksum; then
// ShapeModel::Load as in fuzz_model_loader.cc.
// Seeds: tests/fuzz/corpus/model_payload (small model files written by samp).
#include <cstddef>
#include <cstdint>

#include "libsamp/core/error.h"
#include "libsamp/model/shape_model.h"
#include "libsamp/sdf/vdb_io_testing.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = samp::fuzz::Folder().Write("model.vdb", data, size);
  try {
    samp::ResealVdbForTesting(path);
  } catch (const samp::Error&) {
    // No parsable file metadata: loaded as it is.
  }
  try {
    const samp::ShapeModel model = samp::ShapeModel::Load(path);
    model.Check();
  } catch (const samp::Error&) {
  }
  return 0;
}
