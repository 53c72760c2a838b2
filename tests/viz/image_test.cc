#include "libsamp/viz/image.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "libsamp/core/error.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("samp_viz_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(Image, PngRoundTripKeepsPixelsAndLeavesNoTemporary) {
  const fs::path dir = TempDir("png");
  RgbImage image(31, 17, kWhite);
  image.Set(3, 4, {255, 0, 0});
  image.Set(30, 16, {0, 10, 200});
  const std::string path = (dir / "sub" / "a.png").string();
  WritePng(path, image);
  const RgbImage back = ReadPng(path);
  ASSERT_EQ(back.width, 31);
  ASSERT_EQ(back.height, 17);
  EXPECT_EQ(back.pixels, image.pixels);
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir / "sub")) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1);
  EXPECT_THROW(WritePng((dir / "empty.png").string(), RgbImage()), Error);
  EXPECT_THROW(ReadPng((dir / "missing.png").string()), Error);
  fs::remove_all(dir);
}

TEST(Image, ColourMaps) {
  EXPECT_EQ(Viridis(0.0), (Rgb{68, 1, 84}));
  EXPECT_EQ(Viridis(1.0), (Rgb{253, 231, 37}));
  EXPECT_EQ(Viridis(2.0), Viridis(1.0));
  EXPECT_EQ(Diverging(0.0), (Rgb{247, 247, 247}));
  EXPECT_GT(Diverging(-1.0).b, Diverging(-1.0).r);  // negative is blue
  EXPECT_GT(Diverging(1.0).r, Diverging(1.0).b);    // positive is red
  EXPECT_EQ(PaletteColor(0), PaletteColor(10));
  EXPECT_NE(PaletteColor(0), PaletteColor(1));
  const RgbImage field = ColorizeSigned(std::vector<float>{-1.f, 0.f, 1.f, std::numeric_limits<float>::quiet_NaN()}, 2, 2, 1.0);
  EXPECT_EQ(field.At(0, 0), Diverging(-1));
  EXPECT_EQ(field.At(1, 1), kGray);
}

TEST(Image, TextIsDrawnWhereAligned) {
  RgbImage image(200, 60, kWhite);
  TextStyle style;
  style.size_px = 20;
  style.h_align = HAlign::kRight;
  style.v_align = VAlign::kBottom;
  DrawText(&image, "Hello", 190, 50, style);
  EXPECT_GT(PixelVariance(image), 10.0);
  int text_width = 0;
  MeasureText("Hello", style, &text_width, nullptr);
  EXPECT_GT(text_width, 30);
  // Nothing drawn left of the text box or below its bottom.
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      if (x < 190 - text_width || x >= 190 || y >= 50) EXPECT_EQ(image.At(x, y), kWhite) << x << "," << y;
}

TEST(Image, ComposeAndCrop) {
  RgbImage canvas(50, 40, kWhite);
  RgbImage red(10, 5, Rgb{255, 0, 0});
  Paste(red, 45, 38, &canvas);  // clipped
  EXPECT_EQ(canvas.At(49, 39), (Rgb{255, 0, 0}));
  Paste(red, 5, 6, &canvas);
  const RgbImage cropped = CropToContent(canvas, kWhite, 1);
  EXPECT_EQ(cropped.width, 50 - 5 + 1);
  EXPECT_EQ(cropped.height, 40 - 6 + 1);
  const RgbImage fit = ResizeToFit(canvas, 25, 100);
  EXPECT_EQ(fit.width, 25);
  EXPECT_EQ(fit.height, 20);
  EXPECT_EQ(PixelVariance(RgbImage(5, 5, kGray)), 0.0);
}

}  // namespace
}  // namespace samp
