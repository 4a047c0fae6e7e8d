// `sphfem view SCENE`: a window that runs the scene live, drawn by the screen-space fluid
// renderer. Mouse: left drag orbits, right drag pans, wheel zooms. Keys: space pause/run,
// S one step, R reset, P particles, F fluid surface, M meshes, W wireframe, C camera home,
// Q or Esc quit.
#pragma once

#include <string>

namespace CLI {
class App;
}

struct ViewOptions {
  std::string scene;
  std::string size = "1280x720";  // initial window size
  int threads = 0;                // CPU threads for the simulation, 0 = all cores
};

CLI::App* add_view_command(CLI::App& app, ViewOptions& opt);

// Returns 0 when the window is closed. Without a display (neither $DISPLAY nor
// $WAYLAND_DISPLAY set, or no window can be opened) prints one line suggesting the headless
// commands and returns 2. Throws SceneError / std::runtime_error for a bad scene.
int run_view(const ViewOptions& opt);
