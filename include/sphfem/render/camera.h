// A pinhole camera for the software renderer: pixel (0, 0) is the top-left corner, pixel
// centres sit at (i + 0.5, j + 0.5), and depth is the distance along the viewing axis.
#pragma once

#include "sphfem/core/vec.h"

namespace sphfem::render {

struct Camera {
  Vec3d eye{0, 0, 1};
  Vec3d target{0, 0, 0};
  Vec3d up{0, 1, 0};
  double fov_y_deg = 40.0;  // vertical field of view
  int width = 1280, height = 720;
};

// The camera as an orthonormal frame, computed once per image. A view-space point (x, y, z)
// projects to pixel (cx + focal x / z, cy - focal y / z); z is its depth.
struct ViewFrame {
  Vec3d eye, right, up, forward;
  double focal = 1;  // pixels per unit of x / z
  double cx = 0, cy = 0;

  explicit ViewFrame(const Camera& cam);
  Vec3d to_view(const Vec3d& world) const;
  // World direction of the ray through pixel position (px, py), scaled so that its
  // component along `forward` is 1: the ray parameter is then the depth.
  Vec3d ray(double px, double py) const;
};

struct Projection {
  double x = 0, y = 0;  // pixel position
  double depth = 0;     // > 0 in front of the camera
  bool in_front() const { return depth > 0; }
};

Projection project(const Camera& cam, const Vec3d& world);

// Frames the box [lo, hi] (y up) from the front (+z side, looking along -z), above and a little
// to the side, close enough that the whole box fills the picture with a small margin.
Camera auto_frame(const Vec3d& lo, const Vec3d& hi, int width, int height, double fov_y_deg = 35.0);

}  // namespace sphfem::render
