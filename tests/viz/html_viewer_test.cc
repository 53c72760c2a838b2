// The HTML viewers (libsamp/viz/html_viewer.h): the page's structure and data,
// and in a real browser (headless Chromium; skipped with a message when it is
// not installed) no console errors, a non-blank canvas, the expected meshes and
// point sets, a frame slider that moves the cars, and a screenshot in
// SAMP_TEST_OUTPUT_DIR.
#include "libsamp/viz/html_viewer.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/viz/fit_run.h"
#include "libsamp/viz/image.h"
#include "tests/viz/fit_run_fixture.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The JSON of <script id="samp-data">.
nlohmann::json PageData(const std::string& html) {
  const std::string open = "<script id=\"samp-data\" type=\"application/json\">";
  const size_t begin = html.find(open);
  EXPECT_NE(begin, std::string::npos);
  const size_t end = html.find("</script>", begin);
  return nlohmann::json::parse(html.substr(begin + open.size(), end - begin - open.size()));
}

std::vector<uint8_t> Base64Decode(const std::string& text) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : -1;
  };
  std::vector<uint8_t> out;
  uint32_t buffer = 0;
  int bits = 0;
  for (char c : text) {
    const int v = value(c);
    if (v < 0) continue;
    buffer = (buffer << 6) | uint32_t(v), bits += 6;
    if (bits >= 8) bits -= 8, out.push_back(uint8_t((buffer >> bits) & 0xff));
  }
  return out;
}

TEST(Base64, EncodesTheRfc4648Vectors) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", ""}, {"f", "Zg=="}, {"fo", "Zm8="}, {"foo", "Zm9v"}, {"foob", "Zm9vYg=="}, {"fooba", "Zm9vYmE="},
      {"foobar", "Zm9vYmFy"}};
  for (const auto& [plain, encoded] : cases) EXPECT_EQ(Base64Encode(plain.data(), plain.size()), encoded);
}

class HtmlViewerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = (fs::temp_directory_path() / ("samp_viz_html_" + std::to_string(::getpid()))).string();
    fs::remove_all(root_);
    fixture_ = new testing::FitRunFixture(testing::WriteFitRunFixture(root_));
    run_ = new FitRunView(LoadFitRun(fixture_->output_dir));
  }
  static void TearDownTestSuite() {
    delete run_;
    delete fixture_;
    fs::remove_all(root_);
  }
  static std::string root_;
  static testing::FitRunFixture* fixture_;
  static FitRunView* run_;
};
std::string HtmlViewerTest::root_;
testing::FitRunFixture* HtmlViewerTest::fixture_ = nullptr;
FitRunView* HtmlViewerTest::run_ = nullptr;

TEST_F(HtmlViewerTest, PageInlinesThreeJsAndCarriesTheRun) {
  ASSERT_TRUE(HtmlViewerAvailable()) << "this build has no three.js (install libjs-three and reconfigure)";
  EXPECT_EQ(EmbeddedThreeRevision(), "111");
  const std::string html = FitViewerHtml(*run_);
  EXPECT_NE(html.find("REVISION=\"111\""), std::string::npos);
  EXPECT_NE(html.find("OrbitControls"), std::string::npos);
  // Self-contained: nothing is fetched.
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link "), std::string::npos);
  const nlohmann::json data = PageData(html);
  ASSERT_EQ(data["sequences"].size(), 1u);
  const nlohmann::json& tracks = data["sequences"][0]["tracks"];
  ASSERT_EQ(tracks.size(), fixture_->tracks.size());
  // Poses: 7 floats per frame; the points: int16 xyz per point, offsets per frame.
  for (size_t t = 0; t < tracks.size(); ++t) {
    const std::vector<uint8_t> poses = Base64Decode(tracks[t]["poses"].get<std::string>());
    ASSERT_EQ(poses.size(), 21u * 7u * 4u);
    float x = 0;
    std::memcpy(&x, poses.data() + 7 * 4 * 20, 4);
    EXPECT_NEAR(x, fixture_->tracks[t].fitted_world_from_object[20].translation().x(), 1e-5);
    const auto offsets = tracks[t]["points"]["offsets"].get<std::vector<uint32_t>>();
    ASSERT_EQ(offsets.size(), 22u);
    EXPECT_EQ(offsets.back(), 21u * 3000u);
    EXPECT_EQ(Base64Decode(tracks[t]["points"]["data"].get<std::string>()).size(), 21u * 3000u * 3u * 2u);
    EXPECT_TRUE(tracks[t]["mesh"].contains("errors"));
  }
  EXPECT_EQ(data["sequences"][0]["ground_truth"].size(), fixture_->tracks.size());
  // Subsampling keeps at most max_points_per_frame per frame.
  FitHtmlOptions options;
  options.max_points_per_frame = 500;
  const nlohmann::json small = PageData(FitViewerHtml(*run_, options));
  EXPECT_EQ(small["sequences"][0]["tracks"][0]["points"]["offsets"].back().get<uint32_t>(), 21u * 500u);
}

// ---- In a browser ------------------------------------------------------------------

std::string FindChromium() {
  if (const char* env = std::getenv("SAMP_CHROMIUM")) return env;
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    for (const char* dir : {"/usr/bin/", "/usr/local/bin/", "/snap/bin/"}) {
      const std::string path = std::string(dir) + name;
      if (access(path.c_str(), X_OK) == 0) return path;
    }
  }
  return "";
}

// Runs a command, returns its standard output.
std::string Run(const std::string& command, int* status) {
  std::string output;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) {
    *status = -1;
    return output;
  }
  std::array<char, 65536> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) output.append(buffer.data(), n);
  *status = pclose(pipe);
  return output;
}

std::string ChromiumFlags(const std::string& profile) {
  // Software WebGL (SwiftShader): no GPU or display needed; root needs --no-sandbox.
  return " --headless --no-sandbox --disable-gpu --use-angle=swiftshader --enable-unsafe-swiftshader"
         " --no-first-run --disable-extensions --disable-background-networking --mute-audio"
         " --window-size=1400,820 --user-data-dir=" + profile;
}

// Opens `page`#selftest, returns the page's self-test JSON.
nlohmann::json SelfTest(const std::string& chromium, const std::string& page, const std::string& profile) {
  int status = 0;
  const std::string dom = Run("timeout 180 " + chromium + ChromiumFlags(profile) +
                                  " --virtual-time-budget=20000 --dump-dom 'file://" + page + "#selftest' 2>/dev/null",
                              &status);
  EXPECT_EQ(status, 0) << "chromium exited with " << status;
  const size_t tag = dom.find("id=\"samp-selftest\"");
  const size_t begin = tag == std::string::npos ? tag : dom.find('>', tag);
  if (begin == std::string::npos) {
    ADD_FAILURE() << "no self-test result in the page (the viewer script did not finish); DOM tail: "
                  << dom.substr(dom.size() > 2000 ? dom.size() - 2000 : 0);
    return nlohmann::json::object();
  }
  const size_t end = dom.find("</pre>", begin);
  std::string text = dom.substr(begin + 1, end - begin - 1);
  // --dump-dom escapes &, <, > in text.
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{{"&lt;", "<"}, {"&gt;", ">"}, {"&amp;", "&"}}) {
    for (size_t i = 0; (i = text.find(from, i)) != std::string::npos; i += to.size()) text.replace(i, from.size(), to);
  }
  return nlohmann::json::parse(text);
}

void Screenshot(const std::string& chromium, const std::string& url, const std::string& png, const std::string& profile) {
  int status = 0;
  fs::remove(png);
  Run("timeout 180 " + chromium + ChromiumFlags(profile) + " --virtual-time-budget=20000 --screenshot=" + png + " '" +
          url + "' 2>/dev/null",
      &status);
  ASSERT_TRUE(fs::exists(png)) << "no screenshot " << png;
  EXPECT_GT(PixelVariance(ReadPng(png)), 100.0) << png << " looks blank";
}

TEST_F(HtmlViewerTest, FitPageWorksInHeadlessChromium) {
  const std::string chromium = FindChromium();
  if (chromium.empty()) {
    GTEST_SKIP() << "Chromium not found (install Debian's chromium, or set SAMP_CHROMIUM): browser test skipped";
  }
  const fs::path out = fs::path(SAMP_TEST_OUTPUT_DIR);
  fs::create_directories(out);
  const std::string page = fs::absolute(out / "fit_viewer.html").string();
  WriteFitViewer(page, *run_);
  const std::string profile = (fs::path(root_) / "chromium_profile").string();
  const nlohmann::json result = SelfTest(chromium, page, profile);
  ASSERT_TRUE(result.contains("frame0")) << result.dump();
  EXPECT_TRUE(result["errors"].empty()) << "console errors: " << result["errors"].dump();
  EXPECT_GT(result["nonblank_share"].get<double>(), 0.02) << "the canvas is blank";
  // Every track: one mesh and one point set, all present in the first frame.
  EXPECT_EQ(result["frame0"]["meshes"], int(fixture_->tracks.size()));
  EXPECT_EQ(result["frame0"]["point_sets"], int(fixture_->tracks.size()));
  EXPECT_EQ(result["frame0"]["visible_meshes"], int(fixture_->tracks.size()));
  EXPECT_EQ(result["frame0"]["visible_point_sets"], int(fixture_->tracks.size()));
  // The slider moved to the last frame: the moving cars moved, the points changed.
  EXPECT_EQ(result["slider_frame"], 20);
  EXPECT_GT(result["max_mesh_displacement"].get<double>(), 5.0);
  EXPECT_TRUE(result["point_ranges_changed"].get<bool>());
  const double load_ms = result["load_ms"].get<double>();
  const size_t bytes = fs::file_size(page);
  std::cout << "fit viewer: " << fixture_->tracks.size() << " tracks x 21 frames x 3000 points, page "
            << bytes / 1e6 << " MB, scene ready after " << load_ms << " ms (navigation start to first render; "
            << "marks " << result["marks"].dump() << ")" << std::endl;
  std::ofstream(out / "fit_viewer_load.json") << nlohmann::json{{"load_ms", load_ms}, {"marks", result["marks"]}, {"page_bytes", bytes}}.dump();
  Screenshot(chromium, "file://" + page + "#frame=10", (out / "fit_viewer.png").string(), profile);
}

TEST(InspectViewer, ShippedModelPageWorksInHeadlessChromium) {
  const std::string chromium = FindChromium();
  if (chromium.empty()) {
    GTEST_SKIP() << "Chromium not found (install Debian's chromium, or set SAMP_CHROMIUM): browser test skipped";
  }
  const ShapeModel model = ShapeModel::Load(SAMP_SHIPPED_MODEL);
  const fs::path out = fs::path(SAMP_TEST_OUTPUT_DIR);
  fs::create_directories(out);
  const std::string page = fs::absolute(out / "inspect_viewer.html").string();
  InspectHtmlOptions options;
  options.model_path = SAMP_SHIPPED_MODEL;
  WriteInspectViewer(page, model, options);
  const std::string profile =
      (fs::temp_directory_path() / ("samp_viz_inspect_profile_" + std::to_string(::getpid()))).string();
  const nlohmann::json result = SelfTest(chromium, page, profile);
  ASSERT_TRUE(result.contains("mean_triangles")) << result.dump();
  EXPECT_TRUE(result["errors"].empty()) << "console errors: " << result["errors"].dump();
  EXPECT_EQ(result["components"], model.NumComponents());
  EXPECT_GT(result["mean_triangles"].get<int>(), 1000);
  EXPECT_GT(result["nonblank_share"].get<double>(), 0.02);
  // +2 sigma on the first component changes the surface.
  EXPECT_GT(result["slider_box_change"].get<double>(), 1e-3);
  std::cout << "inspect viewer: scene ready after " << result["load_ms"] << " ms" << std::endl;
  Screenshot(chromium, "file://" + page, (out / "inspect_viewer.png").string(), profile);
  fs::remove_all(profile);
}

}  // namespace
}  // namespace samp
