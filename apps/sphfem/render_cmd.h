// `sphfem render`: pictures (PNG, in OUT/images, one per frame and named like it) or a video
// (OUT/video.mp4, through ffmpeg) of a run folder: the fluid (frames/fluid_NNNNNN.vtu, or .ply
// when the run wrote no VTU) and the bodies' surfaces (frames/bodies_NNNNNN.vtu), in the tank
// of run.json. Drawn by the OpenGL screen-space fluid renderer through headless EGL, or by the
// software splat renderer.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

struct RenderOptions {
  std::string out_dir;  // the folder written by `sphfem run`
  std::string size = "1280x720";
  std::string frames = "all";     // "all", "last" or a frame number (the NNNNNN of the files)
  std::string format = "png";     // png or mp4
  std::string renderer = "auto";  // auto (OpenGL, software if no context), gl, splat
  // Camera overrides, each on its own: they win over run.json's "camera", which wins over
  // the automatic framing of the tank.
  std::vector<double> camera_pos, camera_target;  // empty or x, y, z
  double fov = 0;                                 // vertical, degrees; 0 = not given
  double fps = 0;                                 // mp4 frame rate; 0 = run.json's fps
};

// Adds the `render` subcommand and its options, filling `opt`.
CLI::App* add_render_command(CLI::App& app, RenderOptions& opt);

// Prints each written file, then a last line naming the images folder or the video; returns
// 0. Throws std::runtime_error with a one-line message naming the path and the fix.
int run_render(const RenderOptions& opt);

// `sphfem bench --render`: ms per frame at 1280x720 of a ~65k-particle frame for the OpenGL
// and the software renderer; writes OUT/render.csv when `out_dir` is not empty.
int run_render_bench(const std::string& out_dir);
