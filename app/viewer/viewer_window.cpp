#include "viewer/viewer_window.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "splat/error.h"

namespace app {

struct ViewerWindow::State {
  GLFWwindow* window = nullptr;
  ViewerControls controls = ViewerControls::kLive;
  bool paused = false, snapshot = false, quit = false;
  ViewCamera view;
  bool dragging = false;
  bool panning = false;  // map controls: the drag pans
  double last_x = 0, last_y = 0;
  ViewerInput input;  // map controls, gathered until take_input()
};

bool viewer_built() { return true; }

namespace {

ViewerWindow::State& state_of(GLFWwindow* w) {
  return *static_cast<ViewerWindow::State*>(glfwGetWindowUserPointer(w));
}

void on_map_key(ViewerWindow::State& s, int key, int mods) {
  const int step = (mods & GLFW_MOD_SHIFT) ? 10 : 1;
  if (key == GLFW_KEY_N || key == GLFW_KEY_RIGHT) s.input.camera_step += step;
  if (key == GLFW_KEY_P || key == GLFW_KEY_LEFT) s.input.camera_step -= step;
  if (key == GLFW_KEY_HOME || key == GLFW_KEY_0 || key == GLFW_KEY_KP_0) s.input.overview = true;
  if (key == GLFW_KEY_Q || key == GLFW_KEY_ESCAPE) s.quit = true;
}

void on_key(GLFWwindow* w, int key, int, int action, int mods) {
  ViewerWindow::State& s = state_of(w);
  if (s.controls == ViewerControls::kMap) {
    // Held keys repeat; stepping through cameras by holding n is wanted.
    if (action == GLFW_PRESS || action == GLFW_REPEAT) on_map_key(s, key, mods);
    return;
  }
  if (action != GLFW_PRESS) return;
  if (key == GLFW_KEY_SPACE) s.paused = !s.paused;
  if (key == GLFW_KEY_S) s.snapshot = true;
  if (key == GLFW_KEY_Q || key == GLFW_KEY_ESCAPE) s.quit = true;
  if (key == GLFW_KEY_F) s.view.follow = true;
}

void on_button(GLFWwindow* w, int button, int action, int mods) {
  ViewerWindow::State& s = state_of(w);
  if (s.controls == ViewerControls::kMap) {
    if (action == GLFW_PRESS) {
      s.dragging = true;
      s.panning = button != GLFW_MOUSE_BUTTON_LEFT || (mods & GLFW_MOD_SHIFT);
    } else {
      s.dragging = false;
    }
    glfwGetCursorPos(w, &s.last_x, &s.last_y);
    return;
  }
  if (button != GLFW_MOUSE_BUTTON_LEFT) return;
  s.dragging = action == GLFW_PRESS;
  glfwGetCursorPos(w, &s.last_x, &s.last_y);
}

void on_move(GLFWwindow* w, double x, double y) {
  ViewerWindow::State& s = state_of(w);
  if (!s.dragging) return;
  if (s.controls == ViewerControls::kMap) {
    (s.panning ? s.input.pan_dx : s.input.orbit_dx) += x - s.last_x;
    (s.panning ? s.input.pan_dy : s.input.orbit_dy) += y - s.last_y;
    s.last_x = x;
    s.last_y = y;
    return;
  }
  s.view.follow = false;  // dragging switches to the orbit camera
  s.view.yaw += (x - s.last_x) * 0.01;
  s.view.pitch = std::clamp(s.view.pitch + (y - s.last_y) * 0.01, -1.5, 1.5);
  s.last_x = x;
  s.last_y = y;
}

void on_scroll(GLFWwindow* w, double, double dy) {
  ViewerWindow::State& s = state_of(w);
  if (s.controls == ViewerControls::kMap) {
    s.input.zoom_steps += dy;
    return;
  }
  s.view.follow = false;
  s.view.zoom = std::clamp(s.view.zoom * std::pow(0.9, dy), 0.05, 20.0);
}

}  // namespace

ViewerWindow::ViewerWindow(const std::string& title, ViewerControls controls, int width, int height)
    : state_(std::make_unique<State>()) {
  state_->controls = controls;
  // `gslam live` runs without a window; `gslam view` is nothing without one.
  const std::string headless = controls == ViewerControls::kLive ? ", or use --headless" : "";
  if (!glfwInit()) {
    throw splat::Error("viewer: cannot open a window (no display? set DISPLAY" + headless + ")");
  }
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  state_->window =
      glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!state_->window) {
    glfwTerminate();
    throw splat::Error("viewer: cannot create an OpenGL window" +
                       (headless.empty() ? std::string() : " (use --headless)"));
  }
  glfwMakeContextCurrent(state_->window);
  glfwSwapInterval(0);
  glfwSetWindowUserPointer(state_->window, state_.get());
  glfwSetKeyCallback(state_->window, on_key);
  glfwSetMouseButtonCallback(state_->window, on_button);
  glfwSetCursorPosCallback(state_->window, on_move);
  glfwSetScrollCallback(state_->window, on_scroll);
}

ViewerWindow::~ViewerWindow() {
  glfwDestroyWindow(state_->window);
  glfwTerminate();
}

void ViewerWindow::show(const splat::Image8& picture, const std::string& title,
                        splat::Image8* capture) {
  glfwSetWindowTitle(state_->window, title.c_str());
  int fb_w = 0, fb_h = 0;
  glfwGetFramebufferSize(state_->window, &fb_w, &fb_h);
  glViewport(0, 0, fb_w, fb_h);
  glClearColor(0.f, 0.f, 0.f, 1.f);
  glClear(GL_COLOR_BUFFER_BIT);
  // glDrawPixels fills rows bottom-up: flip the top-down picture.
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glRasterPos2f(-1.f, 1.f);
  glPixelZoom(1.f, -1.f);
  glDrawPixels(picture.width, picture.height, GL_RGB, GL_UNSIGNED_BYTE, picture.data.data());
  glFinish();
  if (capture) {
    // Read back the frame just drawn, before the swap leaves the back buffer undefined.
    splat::Image8 bottom_up(fb_w, fb_h, 3);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glReadPixels(0, 0, fb_w, fb_h, GL_RGB, GL_UNSIGNED_BYTE, bottom_up.data.data());
    *capture = splat::Image8(fb_w, fb_h, 3);
    for (int y = 0; y < fb_h; ++y) {
      for (int x = 0; x < fb_w; ++x) {
        for (int c = 0; c < 3; ++c) capture->at(x, y, c) = bottom_up.at(x, fb_h - 1 - y, c);
      }
    }
  }
  glfwSwapBuffers(state_->window);
}

void ViewerWindow::poll() { glfwPollEvents(); }
void ViewerWindow::wait(double seconds) { glfwWaitEventsTimeout(seconds); }

bool ViewerWindow::closed() const { return state_->quit || glfwWindowShouldClose(state_->window); }
bool ViewerWindow::paused() const { return state_->paused; }

bool ViewerWindow::take_snapshot_request() {
  const bool requested = state_->snapshot;
  state_->snapshot = false;
  return requested;
}

ViewCamera ViewerWindow::view() const { return state_->view; }

ViewerInput ViewerWindow::take_input() {
  ViewerInput input = std::exchange(state_->input, ViewerInput{});
  GLFWwindow* w = state_->window;
  auto held = [w](int key) { return glfwGetKey(w, key) == GLFW_PRESS ? 1 : 0; };
  input.fly = Eigen::Vector3i(held(GLFW_KEY_D) - held(GLFW_KEY_A),
                              held(GLFW_KEY_R) + held(GLFW_KEY_PAGE_UP) - held(GLFW_KEY_F) -
                                  held(GLFW_KEY_PAGE_DOWN),
                              held(GLFW_KEY_W) - held(GLFW_KEY_S))
                  .cwiseMax(-1)
                  .cwiseMin(1);
  input.fast = held(GLFW_KEY_LEFT_SHIFT) || held(GLFW_KEY_RIGHT_SHIFT);
  return input;
}

}  // namespace app
