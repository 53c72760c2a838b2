// Fuzz target: the CAD manifest reader (JSON, LoadManifest) and the lookup of
// an entry in what it returns.
// Seeds: tests/fuzz/corpus/manifest (models/cad_manifest.json and small variants).
#include <cstddef>
#include <cstdint>

#include "libsamp/core/error.h"
#include "libsamp/scan/canonical.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = samp::fuzz::Folder().Write("manifest.json", data, size);
  try {
    const samp::Manifest manifest = samp::LoadManifest(path);
    for (const samp::ManifestEntry& entry : manifest.entries) manifest.Find(entry.file);
  } catch (const samp::Error&) {
  }
  return 0;
}
