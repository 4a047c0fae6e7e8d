#include "view_cmd.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <string>

#if defined(SPHFEM_HAS_GLFW)
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include "sphfem/couple/ray_coupling.h"
#include "sphfem/fem/solver.h"
#include "sphfem/render/camera.h"
#include "sphfem/render/fluid_gl.h"
#include "sphfem/render/frame_io.h"
#include "sphfem/scene/bodies.h"
#include "sphfem/scene/load.h"
#include "sphfem/sim/body_frames.h"
#include "sphfem/sim/simulation.h"
#include "sphfem/sph/solver.h"
#endif

namespace {

bool env_set(const char* var) {
  const char* v = std::getenv(var);
  return v && *v;
}

// One line, and exit code 2 like any other input the command cannot use.
int no_display(const std::string& scene, const std::string& why) {
  std::fprintf(stderr,
               "error: sphfem view needs a display (%s); for pictures without one run `sphfem "
               "run %s --render` or `sphfem render OUTDIR`\n",
               why.c_str(), scene.c_str());
  return 2;
}

}  // namespace

CLI::App* add_view_command(CLI::App& app, ViewOptions& opt) {
  auto* v = app.add_subcommand("view", "run a scene live in a window (orbit, pause, step, reset)");
  v->add_option("scene", opt.scene, "scene file (JSON)")->required();
  v->add_option("--size", opt.size, "window size WIDTHxHEIGHT (default 1280x720)");
  v->add_option("--threads", opt.threads, "CPU threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  return v;
}

#if !defined(SPHFEM_HAS_GLFW)

int run_view(const ViewOptions& opt) {
  if (!env_set("DISPLAY") && !env_set("WAYLAND_DISPLAY"))
    return no_display(opt.scene, "$DISPLAY and $WAYLAND_DISPLAY are not set");
  return no_display(opt.scene,
                    "this sphfem was built without GLFW; run scripts/install-deps.sh "
                    "and rebuild");
}

#else

namespace {

using namespace sphfem;
using Clock = std::chrono::steady_clock;

// The scene's solvers (sim/simulation.h), stepped as `sphfem run` steps them.
class LiveScene {
 public:
  explicit LiveScene(const SceneSpec& scene) : scene_(scene) { reset(); }

  void reset() {
    sim_.reset();
    frames_.reset();
    sim_ = std::make_unique<Simulation>(scene_, Backend::Cpu);
    if (sim_->bodies()) frames_ = std::make_unique<BodyFrames>(sim_->bodies()->model());
    steps_ = 0;
    error_.clear();
  }

  // One step; a blow-up stops the scene with its message instead of ending the program.
  bool step() {
    if (!error_.empty()) return false;
    try {
      sim_->step(scene_.simulation.dt_max);
      ++steps_;
      return true;
    } catch (const BodyStepError&) {
      error_ = "a body became non-finite (NaN); lower simulation.dt_max";
    } catch (const std::exception& e) { error_ = e.what(); }
    return false;
  }

  void fill(render::RenderFrame& f) {
    f.radius = float(scene_.fluid.particle_radius);
    f.has_box = true;
    f.box_lo = scene_.domain.lo;
    f.box_hi = scene_.domain.hi;
    f.particles.clear();
    if (sim_->fluid()) {
      sim_->snapshot(snap_);
      f.particles.resize(3 * std::size_t(snap_.n));
      for (int i = 0; i < snap_.n; ++i)
        for (int c = 0; c < 3; ++c) f.particles[3 * std::size_t(i) + c] = float(snap_.x[i][c]);
    }
    f.meshes.clear();
    if (BodySolver* bodies = sim_->bodies()) {
      bodies->snapshot(body_snap_);
      f.meshes = render::body_meshes(frames_->surface(body_snap_));
    }
    if (!sim_->obstacles().empty())
      for (render::TriangleMesh& m :
           render::obstacle_meshes(obstacle_surface(sim_->obstacles(), sim_->time())))
        f.meshes.push_back(std::move(m));
  }

  double time() const { return sim_->time(); }
  long steps() const { return steps_; }
  int particles() const { return sim_->fluid() ? sim_->fluid()->count() : 0; }
  const std::string& error() const { return error_; }

 private:
  const SceneSpec& scene_;
  std::unique_ptr<Simulation> sim_;
  std::unique_ptr<BodyFrames> frames_;
  FluidSnapshot snap_;
  BodySnapshot body_snap_;
  long steps_ = 0;
  std::string error_;
};

// A camera circling a target: azimuth about +y, elevation above the horizon, distance.
struct Orbit {
  Vec3d target;
  double azimuth = 0, elevation = 0.3, distance = 1, fov = 35;

  static Orbit from(const render::Camera& c) {
    Orbit o;
    o.target = c.target;
    const Vec3d d = c.eye - c.target;
    o.distance = std::max(norm(d), 1e-6);
    o.elevation = std::asin(std::clamp(d.y / o.distance, -1.0, 1.0));
    o.azimuth = std::atan2(d.x, d.z);
    o.fov = c.fov_y_deg;
    return o;
  }
  render::Camera camera(int w, int h) const {
    render::Camera c;
    c.target = target;
    c.eye = target + Vec3d(std::sin(azimuth) * std::cos(elevation), std::sin(elevation),
                           std::cos(azimuth) * std::cos(elevation)) *
                         distance;
    c.fov_y_deg = fov;
    c.width = w;
    c.height = h;
    return c;
  }
};

struct ViewState {
  Orbit orbit, home;
  render::FluidStyle style;
  bool paused = false, step_once = false, reset = false, help = true;
  bool dragging = false, panning = false;
  // The cursor as of the last motion event: events arrive in batches between pictures, so
  // the position at the time of a press is the last one seen, not the current one.
  double mx = 0, my = 0;
};

void on_key(GLFWwindow* w, int key, int, int action, int) {
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  auto& s = *static_cast<ViewState*>(glfwGetWindowUserPointer(w));
  switch (key) {
    case GLFW_KEY_SPACE:
      s.paused = !s.paused;
      break;
    case GLFW_KEY_S:
      s.step_once = s.paused = true;
      break;
    case GLFW_KEY_R:
      s.reset = true;
      break;
    case GLFW_KEY_P:
      s.style.particles = !s.style.particles;
      break;
    case GLFW_KEY_F:
      s.style.surface = !s.style.surface;
      break;
    case GLFW_KEY_M:
      s.style.meshes = !s.style.meshes;
      break;
    case GLFW_KEY_W:
      s.style.wireframe = !s.style.wireframe;
      break;
    case GLFW_KEY_C:
      s.orbit = s.home;
      break;
    case GLFW_KEY_H:
      s.help = !s.help;
      break;
    case GLFW_KEY_Q:
    case GLFW_KEY_ESCAPE:
      glfwSetWindowShouldClose(w, GLFW_TRUE);
      break;
    default:
      break;
  }
}

void on_button(GLFWwindow* w, int button, int action, int) {
  auto& s = *static_cast<ViewState*>(glfwGetWindowUserPointer(w));
  const bool down = action == GLFW_PRESS;
  if (button == GLFW_MOUSE_BUTTON_LEFT) s.dragging = down;
  if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE) s.panning = down;
}

void on_cursor(GLFWwindow* w, double x, double y) {
  auto& s = *static_cast<ViewState*>(glfwGetWindowUserPointer(w));
  const double dx = x - s.mx, dy = y - s.my;
  s.mx = x;
  s.my = y;
  if (s.dragging) {
    s.orbit.azimuth -= dx * 0.005;
    s.orbit.elevation = std::clamp(s.orbit.elevation + dy * 0.005, -1.5, 1.5);
  } else if (s.panning) {
    int width = 1, height = 1;
    glfwGetWindowSize(w, &width, &height);
    // One pixel moves the target by one pixel's width at the target's distance.
    const render::ViewFrame f(s.orbit.camera(width, std::max(height, 1)));
    const double px = s.orbit.distance / f.focal;
    s.orbit.target = s.orbit.target - f.right * (dx * px) + f.up * (dy * px);
  }
}

void on_scroll(GLFWwindow* w, double, double dy) {
  auto& s = *static_cast<ViewState*>(glfwGetWindowUserPointer(w));
  s.orbit.distance *= std::pow(0.9, dy);
}

void on_error(int, const char* what) { std::fprintf(stderr, "glfw: %s\n", what); }

}  // namespace

int run_view(const ViewOptions& opt) {
  if (!env_set("DISPLAY") && !env_set("WAYLAND_DISPLAY"))
    return no_display(opt.scene, "$DISPLAY and $WAYLAND_DISPLAY are not set");
  int width = 0, height = 0;
  char tail = 0;
  if (std::sscanf(opt.size.c_str(), "%dx%d%c", &width, &height, &tail) != 2 || width < 64 ||
      height < 64)
    throw std::runtime_error("--size " + opt.size + ": expected WIDTHxHEIGHT, e.g. 1280x720");
  const SceneSpec scene = load_scene(opt.scene);
  if (opt.threads > 0) set_cpu_threads(opt.threads);
  LiveScene live(scene);

  if (!glfwInit()) return no_display(opt.scene, "GLFW cannot connect to it");
  glfwSetErrorCallback(on_error);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  const std::string title = "sphfem view — " + (scene.name.empty() ? opt.scene : scene.name);
  GLFWwindow* window = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!window) {
    glfwTerminate();
    return no_display(opt.scene, "no OpenGL 3.3 core window could be opened on it");
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);

  {
    render::FluidRenderer renderer;
    ViewState state;
    state.home = state.orbit =
        Orbit::from(render::auto_frame(scene.domain.lo, scene.domain.hi, width, height));
    glfwSetWindowUserPointer(window, &state);
    glfwSetKeyCallback(window, on_key);
    glfwSetMouseButtonCallback(window, on_button);
    glfwSetCursorPosCallback(window, on_cursor);
    glfwGetCursorPos(window, &state.mx, &state.my);
    glfwSetScrollCallback(window, on_scroll);

    render::RenderFrame frame;
    double rate = 0;  // steps per wall second, over the last half second
    long rate_steps = 0;
    auto rate_t0 = Clock::now();
    while (!glfwWindowShouldClose(window)) {
      glfwPollEvents();
      if (state.reset) {
        live.reset();
        state.reset = false;
      }
      // Step for up to 1/30 s of wall time, so the window keeps answering.
      const auto t0 = Clock::now();
      if (!state.paused) {
        while (std::chrono::duration<double>(Clock::now() - t0).count() < 1.0 / 30 && live.step())
          ++rate_steps;
      } else if (state.step_once) {
        if (live.step()) ++rate_steps;
        state.step_once = false;
      }
      const double since = std::chrono::duration<double>(Clock::now() - rate_t0).count();
      if (since > 0.5) {
        rate = rate_steps / since;
        rate_steps = 0;
        rate_t0 = Clock::now();
      }

      int fw = 0, fh = 0;
      glfwGetFramebufferSize(window, &fw, &fh);
      if (fw > 0 && fh > 0) {
        live.fill(frame);
        renderer.render(frame, state.orbit.camera(fw, fh), state.style, 0);
        char line[256];
        std::snprintf(line, sizeof line, "t = %.3f s   %.0f steps/s   %d particles   %s",
                      live.time(), rate, live.particles(),
                      !live.error().empty() ? "STOPPED"
                      : state.paused        ? "paused"
                                            : "running");
        const int scale = fh >= 900 ? 3 : 2;
        renderer.draw_text(line, 8, 8, scale, 0, fw, fh);
        if (!live.error().empty())
          renderer.draw_text(live.error().substr(0, 160), 8, 8 + 10 * scale, scale, 0, fw, fh);
        else if (state.help) {
          renderer.draw_text("drag orbit  right-drag pan  wheel zoom  c home  h help  q quit", 8,
                             fh - 8 - 20 * scale, scale, 0, fw, fh);
          renderer.draw_text(
              "space run/pause  s step  r reset  p particles  f surface  m meshes  "
              "w wireframe",
              8, fh - 8 - 9 * scale, scale, 0, fw, fh);
        }
        glfwSwapBuffers(window);
        // Let the picture finish before the next steps: on llvmpipe it is drawn by threads
        // that would otherwise fight the simulation's OpenMP threads for the same cores.
        glFinish();
      }
    }
  }
  glfwDestroyWindow(window);
  glfwTerminate();
  return 0;
}

#endif
