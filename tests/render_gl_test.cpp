// The OpenGL screen-space fluid renderer, headless through EGL (Mesa's llvmpipe on a machine
// without a GPU): water lands where the particles project and nowhere else, bodies where
// their triangles project, smoothing flattens a flat surface's normals, thickness is the
// water's volume per unit area, and the same input gives the same bytes. No context is a
// failure, not a skip: every supported machine has Mesa (scripts/install-deps.sh).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <set>
#include <vector>

#include "sphfem/render/headless.h"
#include "sphfem/render/matrices.h"

namespace sphfem::render {
namespace {

std::unique_ptr<HeadlessRenderer> make_renderer() {
  try {
    return std::make_unique<HeadlessRenderer>();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "no headless OpenGL 3.3 context: " << e.what()
                  << " (scripts/install-deps.sh installs Mesa's EGL and llvmpipe)";
    return nullptr;
  }
}

Camera front_camera(int w = 320, int h = 240) {
  Camera cam;
  cam.eye = Vec3d(0.3, 0.4, 3);
  cam.target = Vec3d(0, 0, 0);
  cam.width = w;
  cam.height = h;
  return cam;
}

// Only what is asked for: no floor and no tank, so that anything drawn over the sky is it.
FluidStyle bare_style() {
  FluidStyle s;
  s.floor = false;
  s.tank = false;
  return s;
}

bool differs(const Image& a, const Image& b, int x, int y) {
  const std::uint8_t *p = a.at(x, y), *q = b.at(x, y);
  for (int c = 0; c < 3; ++c)
    if (std::abs(int(p[c]) - int(q[c])) > 2) return true;
  return false;
}

void add_block(std::vector<float>& x, const Vec3d& origin, int nx, int ny, int nz, double spacing) {
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        x.push_back(float(origin.x + i * spacing));
        x.push_back(float(origin.y + j * spacing));
        x.push_back(float(origin.z + k * spacing));
      }
}

TEST(RenderGl, FluidAppearsWhereParticlesProjectAndNowhereElse) {
  auto r = make_renderer();
  ASSERT_TRUE(r);
  const Camera cam = front_camera();
  RenderFrame frame;
  frame.radius = 0.04f;
  add_block(frame.particles, Vec3d(-0.8, -0.3, 0), 3, 3, 3, 0.08);
  add_block(frame.particles, Vec3d(0.4, 0.3, -0.5), 4, 2, 2, 0.08);
  for (const Vec3d& p : {Vec3d(-0.2, 0.6, 0.2), Vec3d(0.7, -0.6, 0.5), Vec3d(0.1, -0.1, -1)})
    frame.particles.insert(frame.particles.end(), {float(p.x), float(p.y), float(p.z)});
  const Image empty = r->render(RenderFrame(), cam, bare_style());
  const Image img = r->render(frame, cam, bare_style());
  const std::vector<float> depth = r->passes().fluid_depth();
  ASSERT_EQ(depth.size(), std::size_t(cam.width) * cam.height);

  // Centre and sprite radius of every particle, from the renderer's own matrices.
  struct Disc {
    double x, y, r;
  };
  std::vector<Disc> discs;
  const Mat4 &view = r->passes().view(), &proj = r->passes().projection();
  for (std::size_t i = 0; i < frame.particle_count(); ++i) {
    const Vec3d p(frame.particles[3 * i], frame.particles[3 * i + 1], frame.particles[3 * i + 2]);
    const PixelPoint q = to_pixel(view, proj, cam.width, cam.height, p);
    ASSERT_GT(q.depth, 0);
    const double f = 0.5 * cam.height * proj(1, 1);
    discs.push_back({q.x, q.y, frame.radius * f / q.depth});
  }
  // Each particle's centre pixel is water.
  for (const Disc& d : discs) {
    const int x = int(std::floor(d.x)), y = int(std::floor(d.y));
    ASSERT_TRUE(x >= 0 && y >= 0 && x < cam.width && y < cam.height);
    EXPECT_GT(depth[std::size_t(y) * cam.width + x], 0.0f) << "no water at " << x << "," << y;
    EXPECT_TRUE(differs(img, empty, x, y)) << "picture unchanged at " << x << "," << y;
  }
  // Nothing beyond the sprites' radius (+10 % for the sphere's true outline off-axis, and
  // 1.5 px of rasterisation), in the depth pass nor in the picture.
  int water = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const bool wet = depth[std::size_t(y) * cam.width + x] > 0;
      water += wet;
      bool near = false;
      for (const Disc& d : discs)
        near = near || std::hypot(x + 0.5 - d.x, y + 0.5 - d.y) <= 1.1 * d.r + 1.5;
      if (!near) {
        EXPECT_FALSE(wet) << "water at " << x << "," << y << " where no particle projects";
        EXPECT_FALSE(differs(img, empty, x, y)) << "picture changed at " << x << "," << y;
      }
    }
  // Not blank: the blocks cover many pixels, and the water is shaded, not flat.
  EXPECT_GT(water, 500);
  std::set<std::uint32_t> colors;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      if (depth[std::size_t(y) * cam.width + x] > 0) {
        const std::uint8_t* p = img.at(x, y);
        colors.insert(std::uint32_t(p[0]) << 16 | std::uint32_t(p[1]) << 8 | p[2]);
      }
  EXPECT_GT(colors.size(), 50u);
}

// The 12 triangles of the box [lo, hi], counter-clockwise from outside.
TriangleMesh box_mesh(const Vec3d& lo, const Vec3d& hi) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    for (double v : {i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z})
      m.positions.push_back(float(v));
  m.indices = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
               2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  return m;
}

double segment_distance(double px, double py, const PixelPoint& a, const PixelPoint& b) {
  const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
  const double t = len2 > 0 ? std::clamp(((px - a.x) * dx + (py - a.y) * dy) / len2, 0.0, 1.0) : 0;
  return std::hypot(px - a.x - t * dx, py - a.y - t * dy);
}

// Signed: > 0 inside the projected triangle by that many pixels, < 0 outside.
double inside_by(double px, double py, const PixelPoint& a, const PixelPoint& b,
                 const PixelPoint& c) {
  auto side = [&](const PixelPoint& u, const PixelPoint& v) {
    return (v.x - u.x) * (py - u.y) - (v.y - u.y) * (px - u.x);
  };
  const double s0 = side(a, b), s1 = side(b, c), s2 = side(c, a);
  const bool in = (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
  const double d = std::min({segment_distance(px, py, a, b), segment_distance(px, py, b, c),
                             segment_distance(px, py, c, a)});
  return in ? d : -d;
}

TEST(RenderGl, SolidAppearsWhereTheMeshProjects) {
  auto r = make_renderer();
  ASSERT_TRUE(r);
  const Camera cam = front_camera();
  RenderFrame frame;
  frame.meshes.push_back(box_mesh(Vec3d(-0.5, -0.3, -0.4), Vec3d(0.3, 0.5, 0.2)));
  const Image empty = r->render(RenderFrame(), cam, bare_style());
  const Image img = r->render(frame, cam, bare_style());
  const TriangleMesh& m = frame.meshes[0];
  std::vector<PixelPoint> v;
  for (std::size_t i = 0; i < m.positions.size(); i += 3)
    v.push_back(to_pixel(r->passes().view(), r->passes().projection(), cam.width, cam.height,
                         Vec3d(m.positions[i], m.positions[i + 1], m.positions[i + 2])));
  int inside = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      double best = -1e300;
      for (std::size_t t = 0; t < m.indices.size(); t += 3)
        best = std::max(best, inside_by(x + 0.5, y + 0.5, v[m.indices[t]], v[m.indices[t + 1]],
                                        v[m.indices[t + 2]]));
      if (best > 1.0) {
        ++inside;
        EXPECT_TRUE(differs(img, empty, x, y)) << "no body at " << x << "," << y;
        // The body's own warm colour, lit: red above blue.
        EXPECT_GT(int(img.at(x, y)[0]), int(img.at(x, y)[2])) << x << "," << y;
      } else if (best < -1.0) {
        EXPECT_FALSE(differs(img, empty, x, y)) << "body drawn at " << x << "," << y;
      }
    }
  EXPECT_GT(inside, 2000);
}

// A flat slab of water, 40 x 40 particles wide and 3 layers deep, top at y = 0. The middle
// layer is shifted by half a spacing along x and z, so that seen from above there is no gap.
RenderFrame slab(float radius) {
  RenderFrame f;
  f.radius = radius;
  const double s = 2.0 * radius;
  for (int layer = 0; layer < 3; ++layer) {
    const double shift = layer == 1 ? radius : 0.0;
    add_block(f.particles, Vec3d(-20 * s + shift, -layer * s - radius, -20 * s + shift), 40, 1, 40,
              s);
  }
  return f;
}

// World-space normals of the pixels whose whole 9 x 9 neighbourhood is water.
std::vector<Vec3d> interior_normals(const HeadlessRenderer& r, const Camera& cam) {
  const std::vector<float> depth = r.passes().fluid_depth(), n = r.passes().normals();
  const Mat4 inv = inverse_rigid(r.passes().view());
  std::vector<Vec3d> out;
  for (int y = 4; y < cam.height - 4; ++y)
    for (int x = 4; x < cam.width - 4; ++x) {
      bool all = true;
      for (int dy = -4; dy <= 4 && all; ++dy)
        for (int dx = -4; dx <= 4 && all; ++dx)
          all = depth[std::size_t(y + dy) * cam.width + x + dx] > 0;
      if (!all) continue;
      const std::size_t i = 3 * (std::size_t(y) * cam.width + x);
      out.push_back(transform(inv, Vec3d(n[i], n[i + 1], n[i + 2]), 0.0));
    }
  return out;
}

TEST(RenderGl, SmoothingFlattensTheNormalsOfAFlatSurface) {
  auto r = make_renderer();
  ASSERT_TRUE(r);
  Camera cam = front_camera();
  cam.eye = Vec3d(0, 1.6, 1.6);
  const RenderFrame f = slab(0.02f);
  auto spread = [&](int iterations, Vec3d* mean) {
    FluidStyle style = bare_style();
    style.smoothing_iterations = iterations;
    r->render(f, cam, style);
    const std::vector<Vec3d> n = interior_normals(*r, cam);
    EXPECT_GT(n.size(), 5000u);
    Vec3d m;
    for (const Vec3d& v : n) m = m + v / double(n.size());
    double var = 0;
    for (const Vec3d& v : n) var += norm2(v - m) / double(n.size());
    *mean = m / std::max(norm(m), 1e-12);
    return var;
  };
  Vec3d raw_mean, smooth_mean;
  const double raw = spread(0, &raw_mean);
  const double smooth = spread(4, &smooth_mean);
  // Raw sphere caps scatter the normals; four sweeps leave a fraction of that, pointing up.
  EXPECT_GT(raw, 0.05);
  EXPECT_LT(smooth, 0.25 * raw) << "raw " << raw << ", smoothed " << smooth;
  EXPECT_GT(smooth_mean.y, 0.97);
}

TEST(RenderGl, ThicknessIsTheWaterDepth) {
  auto r = make_renderer();
  ASSERT_TRUE(r);
  Camera cam = front_camera();
  cam.eye = Vec3d(0, 3, 0);
  cam.up = Vec3d(0, 0, -1);
  const float radius = 0.02f;
  r->render(slab(radius), cam, bare_style());
  const std::vector<float> t = r->passes().thickness();
  // Straight down over the middle of the slab: three layers of particles, each standing for
  // (2r)^3 of water per (2r)^2 of area.
  double sum = 0;
  int count = 0;
  for (int y = cam.height / 2 - 20; y < cam.height / 2 + 20; ++y)
    for (int x = cam.width / 2 - 20; x < cam.width / 2 + 20; ++x) {
      sum += t[std::size_t(y) * cam.width + x];
      ++count;
    }
  EXPECT_NEAR(sum / count, 3 * 2 * radius, 0.05 * 3 * 2 * radius);
}

TEST(RenderGl, SameInputGivesTheSameBytes) {
  auto r = make_renderer();
  ASSERT_TRUE(r);
  const Camera cam = front_camera(200, 150);
  RenderFrame frame = slab(0.03f);
  frame.has_box = true;
  frame.box_lo = Vec3d(-1.4, -0.5, -1.4);
  frame.box_hi = Vec3d(1.4, 0.6, 1.4);
  frame.meshes.push_back(box_mesh(Vec3d(-0.2, -0.1, -0.2), Vec3d(0.2, 0.3, 0.2)));
  const Image a = r->render(frame, cam);
  const Image b = r->render(frame, cam);
  EXPECT_EQ(a.rgb, b.rgb);
  // A fresh context draws the same picture too.
  auto other = make_renderer();
  ASSERT_TRUE(other);
  EXPECT_EQ(other->render(frame, cam).rgb, a.rgb);
}

TEST(RenderGl, ParticleModeAndWireframeDrawSomething) {
  auto r = make_renderer();
  ASSERT_TRUE(r);
  const Camera cam = front_camera(160, 120);
  RenderFrame frame = slab(0.03f);
  frame.meshes.push_back(box_mesh(Vec3d(-0.2, 0.1, -0.2), Vec3d(0.2, 0.5, 0.2)));
  FluidStyle style = bare_style();
  const Image surface = r->render(frame, cam, style);
  style.particles = true;
  style.wireframe = true;
  const Image spheres = r->render(frame, cam, style);
  // No screen-space surface in particle mode; the spheres are drawn into the scene instead.
  for (float d : r->passes().fluid_depth()) ASSERT_EQ(d, 0.0f);
  int changed = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) changed += differs(surface, spheres, x, y);
  EXPECT_GT(changed, 100);
}

}  // namespace
}  // namespace sphfem::render
