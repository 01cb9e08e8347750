// The viewer window (GLFW + OpenGL): shows composed pictures, for `gslam live` (live_view.h) and
// `gslam view` (map_view.h). Live controls: space pauses, s saves a snapshot, q or Esc quits, f
// returns to the follow camera; dragging with the mouse orbits the map, the wheel zooms. Map
// controls are gathered as ViewerInput for the caller to apply; q or Esc quits.
#pragma once
#include <memory>
#include <string>

#include <Eigen/Core>

#include "viewer/live_view.h"
#include "splat/image.h"

namespace app {

// Whether this build has the viewer (GLFW and OpenGL were found at configure time).
bool viewer_built();

// Which controls the window has: live's (ViewCamera, pause, snapshot) or the map viewer's.
enum class ViewerControls { kLive, kMap };

// The map viewer's input since the last ViewerWindow::take_input().
struct ViewerInput {
  double orbit_dx = 0, orbit_dy = 0;  // pixels dragged with the left button
  double pan_dx = 0, pan_dy = 0;      // with the right or middle button, or shift + left
  double zoom_steps = 0;              // wheel steps, positive towards the scene
  int camera_step = 0;                // recorded cameras to step: n or Right +1, p or Left -1
                                      // (10 with shift)
  bool overview = false;              // Home or 0 pressed
  // Fly keys held now, each -1, 0 or 1: x right (D) / left (A), y up (R, PageUp) / down (F,
  // PageDown), z forward (W) / back (S).
  Eigen::Vector3i fly = Eigen::Vector3i::Zero();
  bool fast = false;  // shift held
  bool any() const {
    return orbit_dx != 0 || orbit_dy != 0 || pan_dx != 0 || pan_dy != 0 || zoom_steps != 0 ||
           camera_step != 0 || overview || !fly.isZero();
  }
};

class ViewerWindow {
 public:
  // Opens a width x height window; throws splat::Error if the build has no viewer or no display
  // is reachable.
  explicit ViewerWindow(const std::string& title, ViewerControls controls = ViewerControls::kLive,
                        int width = kLiveViewWidth, int height = kLiveViewHeight);
  ~ViewerWindow();
  ViewerWindow(const ViewerWindow&) = delete;
  ViewerWindow& operator=(const ViewerWindow&) = delete;

  // Draws a [height, width, 3] picture (the window's size) and sets the title (the stats line).
  // With `capture`, also reads back what was drawn (the window's framebuffer) into it.
  void show(const splat::Image8& picture, const std::string& title,
            splat::Image8* capture = nullptr);
  // Handles pending input events.
  void poll();
  // Waits for an input event, at most `seconds`, and handles it.
  void wait(double seconds);
  bool closed() const;
  bool paused() const;
  // True once per press of s.
  bool take_snapshot_request();
  ViewCamera view() const;
  // Map controls: the input gathered since the last call (and the fly keys held now).
  ViewerInput take_input();

  struct State;  // window handle and input state (public for the GLFW callbacks)

 private:
  std::unique_ptr<State> state_;
};

}  // namespace app
