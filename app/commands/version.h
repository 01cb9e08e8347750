// What `gslam --version` prints: the release, the git commit it was built from, and what this
// build can do (rasterizer backends, viewer), for bug reports.
#pragma once
#include <string>

namespace app {

const char* gslam_version();     // the project's version (CMakeLists.txt)
const char* gslam_git_commit();  // `git describe --always --dirty` of the source tree at build time

// "gslam 0.1.0 (commit 9e5a218c0b7d)\nbackends: cpu, vulkan\nviewer: yes".
std::string version_text();

}  // namespace app
