#include "sphfem/render/camera.h"

#include <algorithm>
#include <cmath>

namespace sphfem::render {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3d normalized(const Vec3d& v) {
  const double n = norm(v);
  return n > 0 ? v / n : Vec3d(0, 0, -1);
}

struct Bounds {
  double x0, y0, x1, y1;
  bool all_in_front;
};

Bounds corner_bounds(const Camera& cam, const Vec3d& lo, const Vec3d& hi) {
  Bounds b{1e300, 1e300, -1e300, -1e300, true};
  for (int i = 0; i < 8; ++i) {
    const Vec3d p(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    const Projection q = project(cam, p);
    b.all_in_front = b.all_in_front && q.depth > 1e-9;
    b.x0 = std::min(b.x0, q.x);
    b.x1 = std::max(b.x1, q.x);
    b.y0 = std::min(b.y0, q.y);
    b.y1 = std::max(b.y1, q.y);
  }
  return b;
}

}  // namespace

ViewFrame::ViewFrame(const Camera& cam) : eye(cam.eye) {
  forward = normalized(cam.target - cam.eye);
  Vec3d r = cross(forward, cam.up);
  // An up vector along the view direction leaves the roll undefined; any perpendicular will do.
  if (norm2(r) < 1e-24)
    r = cross(forward, std::fabs(forward.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 0, 1));
  right = normalized(r);
  up = cross(right, forward);
  const double half = 0.5 * std::clamp(cam.fov_y_deg, 1e-3, 179.0) * kPi / 180.0;
  focal = 0.5 * cam.height / std::tan(half);
  cx = 0.5 * cam.width;
  cy = 0.5 * cam.height;
}

Vec3d ViewFrame::to_view(const Vec3d& world) const {
  const Vec3d d = world - eye;
  return Vec3d(dot(d, right), dot(d, up), dot(d, forward));
}

Vec3d ViewFrame::ray(double px, double py) const {
  return forward + right * ((px - cx) / focal) - up * ((py - cy) / focal);
}

Projection project(const Camera& cam, const Vec3d& world) {
  const ViewFrame f(cam);
  const Vec3d v = f.to_view(world);
  Projection p;
  p.depth = v.z;
  // Points on or behind the eye plane have no image; report them far off-screen.
  const double z = std::fabs(v.z) > 1e-300 ? v.z : 1e-300;
  p.x = f.cx + f.focal * v.x / z;
  p.y = f.cy - f.focal * v.y / z;
  return p;
}

Camera auto_frame(const Vec3d& lo_in, const Vec3d& hi_in, int width, int height, double fov_y_deg) {
  const Vec3d lo = vmin(lo_in, hi_in), hi = vmax(lo_in, hi_in);
  const double diag = norm(hi - lo) > 0 ? norm(hi - lo) : 1.0;
  Camera cam;
  cam.width = std::max(width, 1);
  cam.height = std::max(height, 1);
  cam.fov_y_deg = std::clamp(fov_y_deg, 1.0, 170.0);
  cam.up = Vec3d(0, 1, 0);
  // 25 degrees to the side and 22 above: both side walls' depth and the floor stay readable.
  const double az = 25.0 * kPi / 180.0, el = 22.0 * kPi / 180.0;
  const Vec3d dir(std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el));
  const double margin = 0.04 * std::min(cam.width, cam.height);

  auto place = [&](const Vec3d& target, double dist) {
    cam.target = target;
    cam.eye = target + dir * dist;
  };
  auto fits = [&](const Bounds& b) {
    return b.all_in_front && b.x0 >= margin && b.x1 <= cam.width - margin && b.y0 >= margin &&
           b.y1 <= cam.height - margin;
  };

  Vec3d target = (lo + hi) * 0.5;
  double dist = 3 * diag;
  // Closest distance that fits, then centre the box's image and fit again: perspective
  // pushes the nearer half of the box off-centre, and a few rounds settle it.
  for (int round = 0; round < 4; ++round) {
    double d0 = 1e-3 * diag, d1 = 1e3 * diag;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (d0 + d1);
      place(target, mid);
      (fits(corner_bounds(cam, lo, hi)) ? d1 : d0) = mid;
    }
    dist = d1;
    place(target, dist);
    if (round == 3) break;
    const Bounds b = corner_bounds(cam, lo, hi);
    const ViewFrame f(cam);
    const double dx = 0.5 * (b.x0 + b.x1) - f.cx, dy = 0.5 * (b.y0 + b.y1) - f.cy;
    target = target + f.right * (dx * dist / f.focal) - f.up * (dy * dist / f.focal);
  }
  return cam;
}

}  // namespace sphfem::render
