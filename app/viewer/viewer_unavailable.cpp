// The viewer of a build without GLFW/OpenGL: `gslam live` then needs --headless, and `gslam
// view` is unavailable.
#include "viewer/viewer_window.h"
#include "splat/error.h"

#include <string>

namespace app {

struct ViewerWindow::State {};

bool viewer_built() { return false; }

ViewerWindow::ViewerWindow(const std::string&, ViewerControls controls, int, int) {
  throw splat::Error(std::string("viewer: this build has no viewer (apt-get install libglfw3-dev libgl-dev)") +
                     (controls == ViewerControls::kLive ? "; use --headless" : ""));
}
ViewerWindow::~ViewerWindow() = default;
void ViewerWindow::show(const splat::Image8&, const std::string&, splat::Image8*) {}
void ViewerWindow::poll() {}
void ViewerWindow::wait(double) {}
bool ViewerWindow::closed() const { return true; }
bool ViewerWindow::paused() const { return false; }
bool ViewerWindow::take_snapshot_request() { return false; }
ViewCamera ViewerWindow::view() const { return {}; }
ViewerInput ViewerWindow::take_input() { return {}; }

}  // namespace app
