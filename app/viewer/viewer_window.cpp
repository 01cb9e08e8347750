#include "viewer/viewer_window.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>

#include "splat/error.h"

namespace app {

struct ViewerWindow::State {
  GLFWwindow* window = nullptr;
  bool paused = false, snapshot = false, quit = false;
  ViewCamera view;
  bool dragging = false;
  double last_x = 0, last_y = 0;
};

bool viewer_built() { return true; }

namespace {

ViewerWindow::State& state_of(GLFWwindow* w) {
  return *static_cast<ViewerWindow::State*>(glfwGetWindowUserPointer(w));
}

void on_key(GLFWwindow* w, int key, int, int action, int) {
  if (action != GLFW_PRESS) return;
  ViewerWindow::State& s = state_of(w);
  if (key == GLFW_KEY_SPACE) s.paused = !s.paused;
  if (key == GLFW_KEY_S) s.snapshot = true;
  if (key == GLFW_KEY_Q || key == GLFW_KEY_ESCAPE) s.quit = true;
  if (key == GLFW_KEY_F) s.view.follow = true;
}

void on_button(GLFWwindow* w, int button, int action, int) {
  ViewerWindow::State& s = state_of(w);
  if (button != GLFW_MOUSE_BUTTON_LEFT) return;
  s.dragging = action == GLFW_PRESS;
  glfwGetCursorPos(w, &s.last_x, &s.last_y);
}

void on_move(GLFWwindow* w, double x, double y) {
  ViewerWindow::State& s = state_of(w);
  if (!s.dragging) return;
  s.view.follow = false;  // dragging switches to the orbit camera
  s.view.yaw += (x - s.last_x) * 0.01;
  s.view.pitch = std::clamp(s.view.pitch + (y - s.last_y) * 0.01, -1.5, 1.5);
  s.last_x = x;
  s.last_y = y;
}

void on_scroll(GLFWwindow* w, double, double dy) {
  ViewerWindow::State& s = state_of(w);
  s.view.follow = false;
  s.view.zoom = std::clamp(s.view.zoom * std::pow(0.9, dy), 0.05, 20.0);
}

}  // namespace

ViewerWindow::ViewerWindow(const std::string& title) : state_(std::make_unique<State>()) {
  if (!glfwInit()) {
    throw splat::Error("viewer: cannot open a window (no display? set DISPLAY, or use --headless)");
  }
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  state_->window =
      glfwCreateWindow(kLiveViewWidth, kLiveViewHeight, title.c_str(), nullptr, nullptr);
  if (!state_->window) {
    glfwTerminate();
    throw splat::Error("viewer: cannot create an OpenGL window (use --headless)");
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

bool ViewerWindow::closed() const { return state_->quit || glfwWindowShouldClose(state_->window); }
bool ViewerWindow::paused() const { return state_->paused; }

bool ViewerWindow::take_snapshot_request() {
  const bool requested = state_->snapshot;
  state_->snapshot = false;
  return requested;
}

ViewCamera ViewerWindow::view() const { return state_->view; }

}  // namespace app
