// Fuzz target: the CAD/mesh path (LoadMesh through assimp, then samp's
// canonicalisation of what it returns). The first byte picks the format by
// extension (.ply, .obj, .off, .stl, .ac), the rest is the file.
// Seeds: tests/fuzz/corpus/mesh (small meshes, first byte = format).
#include <cstddef>
#include <cstdint>

#include "libsamp/core/error.h"
#include "libsamp/scan/canonical.h"
#include "libsamp/scan/mesh_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {"ply", "obj", "off", "stl", "ac"};
  const std::string name = std::string("mesh.") + kExtensions[data[0] % 5];
  const std::string path = samp::fuzz::Folder().Write(name, data + 1, size - 1);
  try {
    const samp::Mesh mesh = samp::LoadMesh(path);
    samp::Canonicalize(mesh, samp::CanonicalizeOptions());
  } catch (const samp::Error&) {
  }
  return 0;
}
