// Software renderer: spheres land exactly where they project, the nearest one wins, the tank
// is drawn around them, and the bytes do not depend on the number of threads.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdint>
#include <set>
#include <vector>

#include "sphfem/render/camera.h"
#include "sphfem/render/splat.h"

namespace sphfem::render {
namespace {

// Water is the only blue thing in the picture: the surroundings are neutral greys.
bool is_water(const Image& img, int x, int y) {
  const std::uint8_t* p = img.at(x, y);
  return int(p[2]) - int(p[0]) >= 40;
}

// Looking at the origin from +z; the box [-0.5, 0.5]^3 sits in the middle of the picture.
Camera front_camera(int w = 320, int h = 240) {
  Camera cam;
  cam.eye = Vec3d(0, 0, 3);
  cam.target = Vec3d(0, 0, 0);
  cam.width = w;
  cam.height = h;
  return cam;
}
const Vec3d kLo(-0.5, -0.5, -0.5), kHi(0.5, 0.5, 0.5);

// Jittered lattice, the same on every run (a fixed linear congruential generator).
std::vector<float> jittered_block(int side, float spacing, const Vec3d& origin) {
  std::vector<float> x;
  std::uint32_t s = 12345;
  auto jitter = [&] {
    s = s * 1664525u + 1013904223u;
    return (float(s >> 8) / float(1 << 24) - 0.5f) * 0.3f * spacing;
  };
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) {
        x.push_back(float(origin.x) + (i + 0.5f) * spacing + jitter());
        x.push_back(float(origin.y) + (j + 0.5f) * spacing + jitter());
        x.push_back(float(origin.z) + (k + 0.5f) * spacing + jitter());
      }
  return x;
}

TEST(RenderSplat, SingleParticleIsWaterAtItsCentreOnly) {
  const Camera cam = front_camera();
  const std::vector<float> x = {0, 0, 0};
  const Image img = render_particles(cam, x, nullptr, 0.1f, kLo, kHi);
  ASSERT_EQ(img.width, 320);
  ASSERT_EQ(img.height, 240);
  const Projection c = project(cam, Vec3d(0, 0, 0));
  EXPECT_TRUE(is_water(img, int(c.x), int(c.y)));
  // Far away, outside the tank: light background.
  const std::uint8_t* far = img.at(5, 5);
  EXPECT_FALSE(is_water(img, 5, 5));
  EXPECT_GT(far[0], 180);
  EXPECT_GT(far[1], 180);
  EXPECT_GT(far[2], 180);
}

TEST(RenderSplat, WaterMaskMatchesProjectedDiscs) {
  const Camera cam = front_camera(640, 480);
  const float r = 0.06f;
  const std::vector<float> x = {0,    0,    0,      0.25f, 0.1f,   0,    -0.2f, -0.15f,
                                0.1f, 0.1f, -0.25f, -0.2f, -0.25f, 0.2f, -0.1f};
  // A sphere's outline seen near the axis is a circle: centre and radius in pixels.
  const ViewFrame vf(cam);
  std::vector<double> disc;
  for (std::size_t p = 0; p < x.size() / 3; ++p) {
    const Vec3d c(x[3 * p], x[3 * p + 1], x[3 * p + 2]);
    const Projection q = project(cam, c);
    const double rpx = vf.focal * r / std::sqrt(norm2(vf.to_view(c)) - double(r) * r);
    disc.insert(disc.end(), {q.x, q.y, rpx});
  }
  for (int ss : {1, 2}) {
    RenderStyle style;
    style.supersample = ss;
    const Image img = render_particles(cam, x, nullptr, r, kLo, kHi, style);
    long inter = 0, uni = 0, drawn = 0;
    for (int j = 0; j < img.height; ++j)
      for (int i = 0; i < img.width; ++i) {
        bool inside = false;
        for (std::size_t k = 0; k < disc.size(); k += 3) {
          const double dx = i + 0.5 - disc[k], dy = j + 0.5 - disc[k + 1];
          inside = inside || dx * dx + dy * dy <= disc[k + 2] * disc[k + 2];
        }
        const bool water = is_water(img, i, j);
        inter += inside && water;
        uni += inside || water;
        drawn += water;
      }
    ASSERT_GT(uni, 0);
    EXPECT_GT(drawn, 2000);
    // Without supersampling the outline is exact up to the perspective stretch off-axis.
    EXPECT_GT(double(inter) / double(uni), ss == 1 ? 0.98 : 0.95)
        << inter << " / " << uni << " with supersample " << ss;
  }
}

TEST(RenderSplat, NearestSphereWinsWhateverTheOrder) {
  const Camera cam = front_camera();
  // A fast (foam-white) particle in front of a still one on the same line of sight.
  const std::vector<float> x = {0, 0, 0, 0, 0, 0.3f};
  const std::vector<float> v = {0, 10};
  const Image img = render_particles(cam, x, &v, 0.08f, kLo, kHi);
  const Projection c = project(cam, Vec3d(0, 0, 0.3));
  // Listing them the other way round gives the same picture.
  const std::vector<float> x2 = {0, 0, 0.3f, 0, 0, 0};
  const std::vector<float> v2 = {10, 0};
  EXPECT_EQ(render_particles(cam, x2, &v2, 0.08f, kLo, kHi).rgb, img.rgb);
  // Still water at the same place is blue; the fast particle in front made it white.
  const std::vector<float> still = {0, 0};
  const Image blue = render_particles(cam, x, &still, 0.08f, kLo, kHi);
  EXPECT_TRUE(is_water(blue, int(c.x), int(c.y)));
  EXPECT_FALSE(is_water(img, int(c.x), int(c.y)));
  EXPECT_GT(img.at(int(c.x), int(c.y))[0], blue.at(int(c.x), int(c.y))[0] + 60);
}

TEST(RenderSplat, BlockOfParticlesInATankIsShadedWater) {
  const Vec3d lo(0, 0, 0), hi(1, 0.8, 0.6);
  const Camera cam = auto_frame(lo, hi, 320, 240);
  const std::vector<float> x = jittered_block(12, 0.03f, Vec3d(0.02, 0, 0.02));
  const Image img = render_particles(cam, x, nullptr, 0.015f, lo, hi);
  long water = 0;
  std::set<std::uint32_t> shades;
  for (int j = 0; j < img.height; ++j)
    for (int i = 0; i < img.width; ++i)
      if (is_water(img, i, j)) {
        ++water;
        const std::uint8_t* p = img.at(i, j);
        shades.insert(std::uint32_t(p[0]) << 16 | std::uint32_t(p[1]) << 8 | p[2]);
      }
  EXPECT_GT(water, img.width * img.height / 50);
  EXPECT_GT(shades.size(), 100u) << "spheres should be shaded, not flat";
  // The midpoint of the front top edge is drawn dark.
  const Projection e = project(cam, Vec3d(0.5, 0.8, 0.6));
  const std::uint8_t* p = img.at(int(e.x), int(e.y));
  EXPECT_LT(int(p[0]) + p[1] + p[2], 3 * 150);
}

TEST(RenderSplat, SameBytesWithOneOrTwoThreads) {
  const Vec3d lo(0, 0, 0), hi(0.8, 0.5, 0.4);
  const Camera cam = auto_frame(lo, hi, 480, 270);
  const std::vector<float> x = jittered_block(20, 0.012f, Vec3d(0.01, 0, 0.01));
  std::vector<float> v(x.size() / 3);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = float(i % 97) * 0.04f;
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const Image one = render_particles(cam, x, &v, 0.006f, lo, hi);
  omp_set_num_threads(2);
  const Image two = render_particles(cam, x, &v, 0.006f, lo, hi);
  omp_set_num_threads(3);
  const Image three = render_particles(cam, x, &v, 0.006f, lo, hi);
  omp_set_num_threads(before);
  EXPECT_EQ(one.rgb, two.rgb);
  EXPECT_EQ(one.rgb, three.rgb);
}

TEST(RenderSplat, RejectsMalformedInput) {
  const Camera cam = front_camera();
  const std::vector<float> bad = {0, 0};
  EXPECT_THROW(render_particles(cam, bad, nullptr, 0.1f, kLo, kHi), std::invalid_argument);
  const std::vector<float> x = {0, 0, 0};
  const std::vector<float> v = {1, 2};
  EXPECT_THROW(render_particles(cam, x, &v, 0.1f, kLo, kHi), std::invalid_argument);
  EXPECT_THROW(render_particles(cam, x, nullptr, 0.0f, kLo, kHi), std::invalid_argument);
  // No particles: just the tank.
  EXPECT_NO_THROW(render_particles(cam, {}, nullptr, 0.0f, kLo, kHi));
}

TEST(RenderSplat, StrayParticlesDoNotBreakThePicture) {
  const Camera cam = front_camera(160, 120);
  const float nan = std::nanf("");
  // Not finite, very far, behind the eye, straddling the eye plane, filling the view.
  const std::vector<float> x = {nan, 0, 0, 1e30f, 0, 0, 0, 0, 5, 0, 0, 2.95f, 0, 0, 2.8f, 0, 0, 0};
  const std::vector<float> v = {nan, 1, 1e30f, -1, nan, 0};
  const Image img = render_particles(cam, x, &v, 0.1f, kLo, kHi);
  EXPECT_EQ(img.rgb.size(), 160u * 120u * 3u);
  // The particle 0.2 in front of the eye spans 60 degrees: the picture but its corners.
  EXPECT_TRUE(is_water(img, 80, 60));
  EXPECT_TRUE(is_water(img, 2, 60));
  EXPECT_TRUE(is_water(img, 80, 2));
}

}  // namespace
}  // namespace sphfem::render
