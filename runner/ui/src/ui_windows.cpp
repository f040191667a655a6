#include "hapticlab/runner_ui/ui_windows.hpp"

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_opengl2.h>
#include <imgui.h>

#include <cstdlib>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <utility>

namespace hapticlab::runner::ui {

struct Windows::Win {
  GLFWwindow* w = nullptr;
  ImGuiContext* ctx = nullptr;
  int fb_w = 0, fb_h = 0;
  std::vector<unsigned char> pixels;  // last frame, RGB, bottom row first
  double last_time = 0;
  std::vector<unsigned int> chars;  // typed since the last frame (GLFW's character callback)
};

namespace {
// GLFW is initialised once per process and terminated at exit: re-initialising it after
// glfwTerminate fails on some X servers.
bool glfw_ready = false;
}  // namespace

Windows::Windows(const WindowOptions& o) {
  if (!glfw_ready) {
    if (!glfwInit())
      throw std::runtime_error("GLFW cannot start: no display (set DISPLAY or run under xvfb-run)");
    glfw_ready = true;
    std::atexit(glfwTerminate);
  }
  const char* titles[2] = {"HapticLab - participant", "HapticLab - experimenter console"};
  for (int i = 0; i < 2; ++i) {
    glfwWindowHint(GLFW_VISIBLE, o.visible ? GLFW_TRUE : GLFW_FALSE);
    GLFWmonitor* monitor = nullptr;
    if (i == 0 && o.participant_fullscreen) {
      int n = 0;
      GLFWmonitor** ms = glfwGetMonitors(&n);
      monitor = n > 0 ? ms[n - 1] : nullptr;
    }
    auto win = std::make_unique<Win>();
    win->w = glfwCreateWindow(o.width, o.height, titles[i], monitor, nullptr);
    if (!win->w) throw std::runtime_error("GLFW cannot open a window (OpenGL 2 context)");
    glfwMakeContextCurrent(win->w);
    glfwSwapInterval(1);
    win->ctx = ImGui::CreateContext();
    ImGui::SetCurrentContext(win->ctx);
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;  // no imgui.ini next to the study
    // Keys: ImGui 1.86 reads io.KeysDown by the backend's codes (GLFW's, set each frame) and
    // maps its named keys through io.KeyMap; typed text comes from the character callback.
    for (const auto& [named, glfw_key] : {std::pair{ImGuiKey_Enter, GLFW_KEY_ENTER},
                                          {ImGuiKey_KeyPadEnter, GLFW_KEY_KP_ENTER},
                                          {ImGuiKey_Space, GLFW_KEY_SPACE},
                                          {ImGuiKey_Backspace, GLFW_KEY_BACKSPACE},
                                          {ImGuiKey_Delete, GLFW_KEY_DELETE},
                                          {ImGuiKey_LeftArrow, GLFW_KEY_LEFT},
                                          {ImGuiKey_RightArrow, GLFW_KEY_RIGHT},
                                          {ImGuiKey_Home, GLFW_KEY_HOME},
                                          {ImGuiKey_End, GLFW_KEY_END},
                                          {ImGuiKey_Tab, GLFW_KEY_TAB},
                                          {ImGuiKey_Escape, GLFW_KEY_ESCAPE}})
      io.KeyMap[named] = glfw_key;
    glfwSetWindowUserPointer(win->w, win.get());
    glfwSetCharCallback(win->w, [](GLFWwindow* gw, unsigned int c) {
      static_cast<Win*>(glfwGetWindowUserPointer(gw))->chars.push_back(c);
    });
    ImGui::StyleColorsDark();
    ImGui_ImplOpenGL2_Init();
    win->last_time = glfwGetTime();
    wins_.push_back(std::move(win));
  }
}

Windows::~Windows() {
  for (auto& w : wins_) {
    glfwMakeContextCurrent(w->w);
    ImGui::SetCurrentContext(w->ctx);
    ImGui_ImplOpenGL2_Shutdown();
    ImGui::DestroyContext(w->ctx);
    glfwDestroyWindow(w->w);
  }
}

bool Windows::Frame(const ParticipantView& pv, const ConsoleView& cv, ParticipantAction* pa,
                    ConsoleAction* ca, Drawn* pd, Drawn* cd) {
  glfwPollEvents();
  bool open = true;
  for (std::size_t i = 0; i < wins_.size(); ++i) {
    Win& w = *wins_[i];
    if (glfwWindowShouldClose(w.w)) open = false;
    glfwMakeContextCurrent(w.w);
    ImGui::SetCurrentContext(w.ctx);
    ImGuiIO& io = ImGui::GetIO();
    glfwGetFramebufferSize(w.w, &w.fb_w, &w.fb_h);
    int ww = 0, wh = 0;
    glfwGetWindowSize(w.w, &ww, &wh);
    io.DisplaySize = ImVec2(static_cast<float>(ww), static_cast<float>(wh));
    if (ww > 0 && wh > 0)
      io.DisplayFramebufferScale = ImVec2(static_cast<float>(w.fb_w) / static_cast<float>(ww),
                                          static_cast<float>(w.fb_h) / static_cast<float>(wh));
    const double now = glfwGetTime();
    io.DeltaTime = static_cast<float>(std::max(1e-4, now - w.last_time));
    w.last_time = now;
    double mx = 0, my = 0;
    glfwGetCursorPos(w.w, &mx, &my);
    io.MousePos = glfwGetWindowAttrib(w.w, GLFW_HOVERED)
                      ? ImVec2(static_cast<float>(mx), static_cast<float>(my))
                      : ImVec2(-FLT_MAX, -FLT_MAX);
    for (int b = 0; b < 3; ++b) io.MouseDown[b] = glfwGetMouseButton(w.w, b) == GLFW_PRESS;
    for (int k = GLFW_KEY_SPACE; k <= GLFW_KEY_LAST && k < IM_ARRAYSIZE(io.KeysDown); ++k)
      io.KeysDown[k] = glfwGetKey(w.w, k) == GLFW_PRESS;
    for (const unsigned int c : w.chars) io.AddInputCharacter(c);
    w.chars.clear();
    ImGui_ImplOpenGL2_NewFrame();
    ImGui::NewFrame();
    if (i == 0) {
      const auto a = DrawParticipant(pv, pd);
      if (pa) *pa = a;
    } else {
      const auto a = DrawConsole(cv, cd);
      if (ca) *ca = a;
    }
    ImGui::Render();
    glViewport(0, 0, w.fb_w, w.fb_h);
    glClearColor(0, 0, 0, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL2_RenderDrawData(ImGui::GetDrawData());
    w.pixels.resize(static_cast<std::size_t>(w.fb_w) * static_cast<std::size_t>(w.fb_h) * 3);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glReadPixels(0, 0, w.fb_w, w.fb_h, GL_RGB, GL_UNSIGNED_BYTE, w.pixels.data());
    glfwSwapBuffers(w.w);
  }
  return open;
}

void Windows::KeepOpen() {
  for (auto& w : wins_) glfwSetWindowShouldClose(w->w, GLFW_FALSE);
}

void Windows::SaveScreenshot(int window, const std::string& path) const {
  const Win& w = *wins_.at(static_cast<std::size_t>(window));
  if (w.pixels.empty()) throw std::runtime_error("no frame drawn yet");
  cv::Mat rgb(w.fb_h, w.fb_w, CV_8UC3, const_cast<unsigned char*>(w.pixels.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  cv::flip(bgr, bgr, 0);  // OpenGL's first row is the bottom
  if (!cv::imwrite(path, bgr)) throw std::runtime_error(path + ": cannot write the screenshot");
}

}  // namespace hapticlab::runner::ui
