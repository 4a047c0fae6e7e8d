// The OpenGL matrices agree with the software camera: a point lands on the same pixel at the
// same depth, and the clip range keeps the whole box between the near and far planes.
#include <gtest/gtest.h>

#include <cmath>

#include "sphfem/render/camera.h"
#include "sphfem/render/matrices.h"

namespace sphfem::render {
namespace {

Camera oblique_camera() {
  Camera cam;
  cam.eye = Vec3d(2.5, 1.7, 3.1);
  cam.target = Vec3d(0.2, 0.1, -0.3);
  cam.fov_y_deg = 38;
  cam.width = 640;
  cam.height = 360;
  return cam;
}

TEST(RenderMatrices, PixelsMatchTheSoftwareProjection) {
  const Camera cam = oblique_camera();
  const Mat4 view = view_matrix(cam), proj = projection_matrix(cam, 0.1, 50);
  for (const Vec3d& p : {Vec3d(0, 0, 0), Vec3d(0.2, 0.1, -0.3), Vec3d(-1, 2, 0.5),
                         Vec3d(1.5, -0.7, -2), Vec3d(0.01, 0.3, 1.9)}) {
    const PixelPoint q = to_pixel(view, proj, cam.width, cam.height, p);
    const Projection s = project(cam, p);
    EXPECT_NEAR(q.x, s.x, 1e-9);
    EXPECT_NEAR(q.y, s.y, 1e-9);
    EXPECT_NEAR(q.depth, s.depth, 1e-12);
  }
  // The target is the centre of the picture.
  const PixelPoint c = to_pixel(view, proj, cam.width, cam.height, cam.target);
  EXPECT_NEAR(c.x, 320, 1e-9);
  EXPECT_NEAR(c.y, 180, 1e-9);
}

TEST(RenderMatrices, ViewIsRigidAndItsInverseUndoesIt) {
  const Mat4 view = view_matrix(oblique_camera());
  const Mat4 id = inverse_rigid(view) * view;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(id(r, c), r == c ? 1.0 : 0.0, 1e-12);
}

TEST(RenderMatrices, DepthRangeMapsToMinusOneAndOne) {
  const Camera cam = oblique_camera();
  const Mat4 proj = projection_matrix(cam, 0.5, 20);
  for (double d : {0.5, 20.0}) {
    double w = 0;
    const Vec3d clip = transform(proj, Vec3d(0, 0, -d), 1.0, &w);
    EXPECT_NEAR(clip.z / w, d == 0.5 ? -1.0 : 1.0, 1e-12);
  }
}

TEST(RenderMatrices, ClipRangeHoldsTheBox) {
  const Camera cam = oblique_camera();
  const Vec3d lo(-1, -0.5, -1), hi(1, 0.8, 0.6);
  const ClipRange c = clip_range(cam, lo, hi, 4.0);
  const ViewFrame f(cam);
  for (int i = 0; i < 8; ++i) {
    const Vec3d p(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    const double z = f.to_view(p).z;
    EXPECT_GT(z, c.near);
    EXPECT_LT(z, c.far);
  }
  // A low camera sees the floor nearer than any corner of the box.
  Camera low = cam;
  low.eye = Vec3d(0, lo.y + 0.2, 5);
  low.target = Vec3d(0, lo.y, 0);
  EXPECT_LE(clip_range(low, lo, hi, 4.0).near, 0.1 + 1e-12);
  // With the eye inside the box there is still a positive near plane.
  Camera inside = cam;
  inside.eye = Vec3d(0, 0, 0);
  inside.target = Vec3d(1, 0, 0);
  const ClipRange ci = clip_range(inside, lo, hi, 4.0);
  EXPECT_GT(ci.near, 0);
  EXPECT_GT(ci.far, 4.0);
}

}  // namespace
}  // namespace sphfem::render
