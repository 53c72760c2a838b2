// The files the HTML viewers inline, embedded into samp at build time by
// libsamp/viz/embed_assets.cmake: three.js and two of its examples (Debian's
// libjs-three, when installed at configure time) and the viewers' own
// scripts and style sheet (libsamp/viz/html/).
#pragma once

#include <string>

namespace samp::internal {

// The content of an embedded file by name ("three.min.js", "OrbitControls.js",
// "MarchingCubes.js", "fit_viewer.js", "inspect_viewer.js", "viewer.css");
// "" when it was not found at build time.
std::string EmbeddedAsset(const std::string& name);
// The three.js revision (REVISION in three.min.js), "" without three.js.
std::string EmbeddedThreeRevisionString();

}  // namespace samp::internal
