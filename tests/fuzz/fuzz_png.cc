// Fuzz target: the PNG readers of a sequence folder (ReadPngHeader, then
// ReadImage and ReadDisparity under the default memory budget). The first
// byte picks the reader (header only, image as it is, grayscale image,
// disparity map), the rest is the file.
// Seeds: tests/fuzz/corpus/png (small valid PNGs, first byte = reader).
#include <opencv2/imgcodecs.hpp>

#include <cstddef>
#include <cstdint>

#include "libsamp/core/error.h"
#include "libsamp/data/kitti_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const int reader = data[0] % 4;
  const std::string path = samp::fuzz::Folder().Write("input.png", data + 1, size - 1);
  try {
    switch (reader) {
      case 0: samp::ReadPngHeader(path); break;
      case 1: samp::ReadImage(path, cv::IMREAD_UNCHANGED, "image"); break;
      case 2: samp::ReadImage(path, cv::IMREAD_GRAYSCALE, "left image"); break;
      default: samp::ReadDisparity(path); break;
    }
  } catch (const samp::Error&) {
  }
  return 0;
}
