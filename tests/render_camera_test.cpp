// Camera: projection conventions and auto_frame keeping the whole tank in the picture.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sphfem/render/camera.h"

namespace sphfem::render {
namespace {

TEST(RenderCamera, ProjectsTargetToCentreWithDepthAlongView) {
  Camera cam;
  cam.eye = Vec3d(1, 2, 5);
  cam.target = Vec3d(1, 2, 0);
  cam.width = 640;
  cam.height = 480;
  const Projection c = project(cam, cam.target);
  EXPECT_NEAR(c.x, 320, 1e-9);
  EXPECT_NEAR(c.y, 240, 1e-9);
  EXPECT_NEAR(c.depth, 5, 1e-12);
  // y is up in the world and down in the image; +x is to the right.
  EXPECT_LT(project(cam, Vec3d(1, 2.5, 0)).y, 240);
  EXPECT_GT(project(cam, Vec3d(1.5, 2, 0)).x, 320);
  // The top of the field of view lands on the image's top edge.
  const double half = std::tan(cam.fov_y_deg * M_PI / 360.0) * 5;
  EXPECT_NEAR(project(cam, Vec3d(1, 2 + half, 0)).y, 0, 1e-9);
  EXPECT_FALSE(project(cam, Vec3d(1, 2, 6)).in_front());
}

TEST(RenderCamera, AutoFrameKeepsEveryBoxCornerInside) {
  const Vec3d boxes[][2] = {{Vec3d(0, 0, 0), Vec3d(0.8, 0.5, 0.4)},
                            {Vec3d(0, 0, 0), Vec3d(0.2, 0.6, 0.2)},
                            {Vec3d(-2, -1, -3), Vec3d(2, -0.5, 3)},
                            {Vec3d(0, 0, 0), Vec3d(4, 3, 1.5)},
                            {Vec3d(5, 5, 5), Vec3d(5, 5, 5)}};
  const int sizes[][2] = {{1280, 720}, {720, 1280}, {64, 64}};
  for (const auto& box : boxes)
    for (const auto& size : sizes) {
      const Camera cam = auto_frame(box[0], box[1], size[0], size[1]);
      EXPECT_EQ(cam.width, size[0]);
      EXPECT_EQ(cam.height, size[1]);
      double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
      for (int i = 0; i < 8; ++i) {
        const Vec3d p(i & 1 ? box[1].x : box[0].x, i & 2 ? box[1].y : box[0].y,
                      i & 4 ? box[1].z : box[0].z);
        const Projection q = project(cam, p);
        EXPECT_TRUE(q.in_front());
        EXPECT_GE(q.x, 0);
        EXPECT_LE(q.x, size[0]);
        EXPECT_GE(q.y, 0);
        EXPECT_LE(q.y, size[1]);
        x0 = std::min(x0, q.x), x1 = std::max(x1, q.x);
        y0 = std::min(y0, q.y), y1 = std::max(y1, q.y);
      }
      // Framed closely: the box fills most of the width or the height (a point box cannot).
      if (norm(box[1] - box[0]) > 0) {
        EXPECT_GT(std::max((x1 - x0) / size[0], (y1 - y0) / size[1]), 0.8)
            << "box " << box[1].x - box[0].x << " x " << box[1].y - box[0].y;
      }
      // Seen from the front (+z), from above.
      EXPECT_GT(cam.eye.z, box[1].z);
      EXPECT_GT(cam.eye.y, 0.5 * (box[0].y + box[1].y));
    }
}

}  // namespace
}  // namespace sphfem::render
