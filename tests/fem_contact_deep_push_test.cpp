// A push deeper than a thin element is tall: a block whose bottom layer of elements is 1 mm
// thick lands, within one step, 1.5 mm deep in a heavier block (as the dragon-sized bunny's
// head, meshed finer in its crevices, closes onto its body). Pushed back alone, each bottom
// node passes the layer above it and turns its elements inside out; with the volume floor the
// squeezed elements push the layer above up instead. The pushes stay momentum-free and end
// the surfaces apart.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "sphfem/fem/contact.h"
#include "sphfem/fem/mesh.h"
#include "sphfem/fem/model.h"

namespace sphfem {
namespace {

constexpr double kGap = 5e-4, kStart = 8e-4, kDeep = 1.5e-3, kThin = 1e-3;

// The lower block (top at y = 0, four times denser) and the upper one (bottom kStart over it),
// whose middle layer of nodes is moved down to kThin over its bottom.
BodiesModel blocks() {
  Material heavy, light;
  heavy.density = 4000;
  light.density = 1000;
  TetMesh upper = make_box(Vec3d(0.01, kStart, 0.01), Vec3d(0.05, kStart + 0.02, 0.05), 4, 2, 4);
  for (Vec3d& p : upper.x)
    if (std::fabs(p.y - (kStart + 0.01)) < 1e-9) p.y = kStart + kThin;
  return compile_bodies({compile_body(make_box(Vec3d(0, -0.02, 0), Vec3d(0.06, 0, 0.06), 3, 1, 3),
                                      heavy, {}, "lower"),
                         compile_body(upper, light, {}, "upper")},
                        FemSettings());
}

TEST(FemContactDeepPush, ThinLayerPushedThroughItsHeightStaysRightSideOut) {
  const BodiesModel m = blocks();
  ASSERT_EQ(inverted_elements(m, m.x0), 0);
  ContactSettings cs;
  cs.gap = kGap;
  SurfaceContact contact(m, cs);
  const std::vector<Vec3> x_old = m.x0;
  std::vector<Vec3> x = m.x0;
  const int upper0 = m.node_offset[1];
  for (int i = upper0; i < m.nodes; ++i) x[i].y -= Real(kStart + kDeep);  // rigidly, in a step
  ASSERT_EQ(inverted_elements(m, x), 0);
  const std::vector<Vec3> before = x;
  std::vector<Vec3> v(x.size());
  std::vector<std::uint8_t> moved;
  const ContactStats st = contact.resolve(x_old, x, v, 1e-3, moved);

  Vec3d shift;  // sum of m dx: the pushes carry no momentum
  double scale = 0;
  for (int i = 0; i < m.nodes; ++i) {
    shift += Vec3d(x[i] - before[i]) * double(m.mass[i]);
    scale += norm(Vec3d(x[i] - before[i])) * double(m.mass[i]);
  }
  const int turned = inverted_elements(m, x);
  std::printf(
      "[ measured ] %d pairs, %d elements inside out, gap %.3g gaps, momentum %.2g of "
      "sum |m dx|, depth over height %.2f\n",
      st.pairs, turned, st.min_gap / kGap, norm(shift) / scale, st.depth_ratio);
  EXPECT_GT(st.depth_ratio, 1.0);  // the case this is about: a push through an element's height
  EXPECT_EQ(turned, 0);
  // Four detections of 16 sweeps leave the deepest pair 0.885 gaps apart, from 3 gaps behind
  // (what is left, the next step and the bodies' halved steps take up).
  EXPECT_GE(st.min_gap, 0.8 * kGap);
  EXPECT_LT(norm(shift), 1e-4 * scale);  // float round-off over some thousand pushes
}

}  // namespace
}  // namespace sphfem
