#include "sphfem/render/matrices.h"

#include <algorithm>
#include <cmath>

namespace sphfem::render {

std::array<float, 16> Mat4::to_float() const {
  std::array<float, 16> f;
  for (std::size_t i = 0; i < 16; ++i) f[i] = float(m[i]);
  return f;
}

Mat4 operator*(const Mat4& a, const Mat4& b) {
  Mat4 c;
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k) {
      double s = 0;
      for (int i = 0; i < 4; ++i) s += a(r, i) * b(i, k);
      c(r, k) = s;
    }
  return c;
}

Vec3d transform(const Mat4& a, const Vec3d& p, double w, double* w_out) {
  double out[4];
  for (int r = 0; r < 4; ++r) out[r] = a(r, 0) * p.x + a(r, 1) * p.y + a(r, 2) * p.z + a(r, 3) * w;
  if (w_out) *w_out = out[3];
  return Vec3d(out[0], out[1], out[2]);
}

Mat4 view_matrix(const Camera& cam) {
  // The same frame the software renderer uses, with eye space's z pointing backwards.
  const ViewFrame f(cam);
  Mat4 v;
  const Vec3d rows[3] = {f.right, f.up, -f.forward};
  for (int r = 0; r < 3; ++r) {
    v(r, 0) = rows[r].x;
    v(r, 1) = rows[r].y;
    v(r, 2) = rows[r].z;
    v(r, 3) = -dot(rows[r], f.eye);
  }
  v(3, 3) = 1;
  return v;
}

Mat4 projection_matrix(const Camera& cam, double near, double far) {
  const double half = 0.5 * std::clamp(cam.fov_y_deg, 1e-3, 179.0) * 3.14159265358979323846 / 180;
  const double f = 1.0 / std::tan(half);
  const double aspect = double(std::max(cam.width, 1)) / double(std::max(cam.height, 1));
  Mat4 p;
  p(0, 0) = f / aspect;
  p(1, 1) = f;
  p(2, 2) = (far + near) / (near - far);
  p(2, 3) = 2 * far * near / (near - far);
  p(3, 2) = -1;
  return p;
}

Mat4 inverse_rigid(const Mat4& v) {
  Mat4 inv;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) inv(r, c) = v(c, r);
  for (int r = 0; r < 3; ++r)
    inv(r, 3) = -(inv(r, 0) * v(0, 3) + inv(r, 1) * v(1, 3) + inv(r, 2) * v(2, 3));
  inv(3, 3) = 1;
  return inv;
}

ClipRange clip_range(const Camera& cam, const Vec3d& lo, const Vec3d& hi, double floor_reach) {
  const ViewFrame f(cam);
  const double diag = std::max(norm(hi - lo), 1e-6);
  double zmin = 1e300, zmax = -1e300;
  for (int i = 0; i < 8; ++i) {
    const Vec3d p(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    const double z = f.to_view(p).z;
    zmin = std::min(zmin, z);
    zmax = std::max(zmax, z);
  }
  ClipRange c;
  c.far = std::max(zmax, 0.0) + diag + floor_reach;
  // Inside or behind the box the nearest corner says nothing; fall back to a fraction of
  // the box, small enough for an orbit close to the water. The floor (at lo.y) comes
  // closer than the box under a low camera: no nearer than the eye's height above it.
  double near = 0.5 * zmin;
  if (floor_reach > 0 && cam.eye.y > lo.y) near = std::min(near, 0.5 * (cam.eye.y - lo.y));
  c.near = std::max({near, 1e-3 * diag, 1e-5 * c.far});
  return c;
}

PixelPoint to_pixel(const Mat4& view, const Mat4& proj, int width, int height, const Vec3d& p) {
  const Vec3d e = transform(view, p);
  double w = 1;
  const Vec3d clip = transform(proj, e, 1.0, &w);
  PixelPoint q;
  q.depth = -e.z;
  const double iw = std::fabs(w) > 1e-300 ? 1.0 / w : 1e300;
  q.x = (clip.x * iw * 0.5 + 0.5) * width;
  q.y = (0.5 - clip.y * iw * 0.5) * height;
  return q;
}

}  // namespace sphfem::render
