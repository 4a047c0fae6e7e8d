// `sphfem render`: pictures of a run folder's frames (OUT/fluid.pvd) as PNG files in
// OUT/images, one per frame and named like it, drawn by the software renderer.
#pragma once

#include <string>

struct RenderOptions {
  std::string out_dir;  // the folder written by `sphfem run`
  int width = 1280, height = 720;
  std::string frames = "all";  // "all", "last" or a frame number (the NNNNNN of fluid_NNNNNN)
};

// Prints each written image path, then a last line naming the images folder; returns 0.
// Throws std::runtime_error with a one-line message naming the path and the fix.
int run_render(const RenderOptions& opt);
