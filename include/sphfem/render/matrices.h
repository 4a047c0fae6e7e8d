// The camera as OpenGL matrices (column-major, right-handed eye space looking along -z), so
// that a point lands on the same pixel as render::project puts it: pixel (0, 0) is the
// top-left corner and NDC y points up.
#pragma once

#include <array>

#include "sphfem/core/vec.h"
#include "sphfem/render/camera.h"

namespace sphfem::render {

// m[c * 4 + r] is row r of column c, the layout glUniformMatrix4fv takes untransposed.
struct Mat4 {
  std::array<double, 16> m{};
  double& operator()(int r, int c) { return m[std::size_t(c * 4 + r)]; }
  double operator()(int r, int c) const { return m[std::size_t(c * 4 + r)]; }
  std::array<float, 16> to_float() const;
};

Mat4 operator*(const Mat4& a, const Mat4& b);
// Homogeneous transform of (p, w); the fourth component of the result goes to `w_out`.
Vec3d transform(const Mat4& a, const Vec3d& p, double w = 1.0, double* w_out = nullptr);

Mat4 view_matrix(const Camera& cam);
// Perspective with the camera's vertical field of view and aspect width / height, depth
// range [near, far] mapped to NDC [-1, 1].
Mat4 projection_matrix(const Camera& cam, double near, double far);
Mat4 inverse_rigid(const Mat4& view);  // inverse of a rotation + translation

struct ClipRange {
  double near = 0.01, far = 100;
};
// Near and far planes that keep the box [lo, hi] and a floor at lo.y reaching `floor_reach`
// beyond it (none when 0) in view, with the near plane as far out as it can go, for depth
// precision.
ClipRange clip_range(const Camera& cam, const Vec3d& lo, const Vec3d& hi, double floor_reach);

// Pixel position (top-left origin, centres at i + 0.5) and eye depth of a world point under
// view and projection matrices; depth <= 0 means behind the eye.
struct PixelPoint {
  double x = 0, y = 0, depth = 0;
};
PixelPoint to_pixel(const Mat4& view, const Mat4& proj, int width, int height, const Vec3d& p);

}  // namespace sphfem::render
