// Fuzz target: the KITTI text readers of a sequence folder. The first byte
// picks the reader (calibration, object labels, tracking labels, road plane,
// poses), the rest is the file.
// Seeds: tests/fuzz/corpus/kitti_text (one valid file per reader, first byte = reader).
#include <cstddef>
#include <cstdint>

#include "libsamp/core/error.h"
#include "libsamp/data/kitti_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const int reader = data[0] % 5;
  const std::string path = samp::fuzz::Folder().Write("input.txt", data + 1, size - 1);
  try {
    switch (reader) {
      case 0: samp::ReadCalibration(path); break;
      case 1: samp::ReadLabels(path); break;
      case 2: samp::ReadTrackingLabels(path); break;
      case 3: samp::ReadPlane(path); break;
      default: samp::ReadPoses(path); break;
    }
  } catch (const samp::Error&) {
  }
  return 0;
}
