// The `gslam live` window (GLFW + OpenGL): shows composed live views. Keys: space pauses, s saves
// a snapshot, q or Esc quits, f returns to the follow camera; dragging with the mouse orbits the
// map, the wheel zooms.
#pragma once
#include <memory>
#include <string>

#include "viewer/live_view.h"
#include "splat/image.h"

namespace app {

// Whether this build has the viewer (GLFW and OpenGL were found at configure time).
bool viewer_built();

class ViewerWindow {
 public:
  // Opens the window; throws splat::Error if the build has no viewer or no display is reachable.
  explicit ViewerWindow(const std::string& title);
  ~ViewerWindow();
  ViewerWindow(const ViewerWindow&) = delete;
  ViewerWindow& operator=(const ViewerWindow&) = delete;

  // Draws a [kLiveViewHeight, kLiveViewWidth, 3] picture and sets the title (the stats line).
  // With `capture`, also reads back what was drawn (the window's framebuffer) into it.
  void show(const splat::Image8& picture, const std::string& title,
            splat::Image8* capture = nullptr);
  // Handles pending input events.
  void poll();
  bool closed() const;
  bool paused() const;
  // True once per press of s.
  bool take_snapshot_request();
  ViewCamera view() const;

  struct State;  // window handle and input state (public for the GLFW callbacks)

 private:
  std::unique_ptr<State> state_;
};

}  // namespace app
