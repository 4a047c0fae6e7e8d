// Which same-body pairs the surface contact counts, on a sheet one cell thick moved by hand
// for one step: a crease, whose inside presses faces a ring apart together, is held apart; a
// vertex slid along its own sheet beside a face a ring away is left alone. Either rule
// alone fails one of the two: faces within a rest edge never counting lets the crease pass
// through itself (as the paper's heavy tube's wall did, buckled by the water jet), and only
// faces within three gaps exempted pushes the sliding vertex off its sheet (as the bunny's
// fold did, wrinkling until elements inverted). And the two sides of a crevice, closer at
// rest than either rule's radius, are held from passing through each other as it closes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "sphfem/fem/contact.h"
#include "sphfem/fem/import.h"
#include "sphfem/fem/mesh.h"
#include "sphfem/fem/model.h"

namespace sphfem {
namespace {

constexpr double kCell = 0.01, kThick = 0.01, kGap = 0.001;
constexpr int kNx = 20, kNz = 5;

BodiesModel sheet() {
  FemSettings set;
  Material mat;
  mat.young = 1e4;
  return compile_bodies(
      {compile_body(make_box(Vec3d(0, 0, 0), Vec3d(kNx * kCell, kThick, kNz * kCell), kNx, 1, kNz),
                    mat)},
      set);
}

int node_at(const BodiesModel& m, double x, double y, double z) {
  for (std::size_t i = 0; i < m.x0.size(); ++i)
    if (norm(Vec3d(m.x0[i]) - Vec3d(x, y, z)) < 1e-6) return int(i);
  return -1;
}

ContactSettings settings() {
  ContactSettings cs;
  cs.gap = kGap;
  return cs;
}

// The right half of the sheet turned by angle a about a line across it, half a cell to the
// right of the middle column and h over the top: at a = pi it lies upside down on the left
// half, 2 h above it, the first rotated column right over the middle one.
std::vector<Vec3> folded(const BodiesModel& m, double a, double h) {
  const double cx = (kNx / 2 + 0.5) * kCell, cy = kThick + h;
  std::vector<Vec3> x = m.x0;
  for (Vec3& p : x) {
    if (!(double(p.x) > cx)) continue;
    const double dx = double(p.x) - cx, dy = double(p.y) - cy;
    p = Vec3(Vec3d(cx + dx * std::cos(a) - dy * std::sin(a),
                   cy + dx * std::sin(a) + dy * std::cos(a), double(p.z)));
  }
  return x;
}

TEST(FemContactNeighbours, CreaseHoldsTheRingsEitherSideOfItApart) {
  const BodiesModel m = sheet();
  SurfaceContact contact(m, settings());
  const double h = 0.3 * kGap;  // the halves end 0.6 gaps apart
  const std::vector<Vec3> x_old = folded(m, 3.14159265358979 - 0.3, h);
  std::vector<Vec3> x = folded(m, 3.14159265358979, h);
  std::vector<Vec3> v(x.size());
  std::vector<std::uint8_t> moved;
  const ContactStats st = contact.resolve(x_old, x, v, 1e-3, moved);
  // Each node of the first rotated column's top lies over the middle column's top node, a
  // cell from it at rest and two surface edges at most from every face around it.
  double closest = 1e9;
  for (int k = 1; k < kNz; ++k) {
    const double z = k * kCell;
    const int over = node_at(m, (kNx / 2 + 1) * kCell, kThick, z);
    const int under = node_at(m, (kNx / 2) * kCell, kThick, z);
    ASSERT_GE(over, 0);
    ASSERT_GE(under, 0);
    closest = std::min(closest, double(norm(x[over] - x[under])));
  }
  std::printf("[ measured ] crease: %d pairs, the rings either side %.3g gaps apart (2 h = %.2g)\n",
              st.pairs, closest / kGap, 2 * h / kGap);
  EXPECT_GT(st.pairs, 0);
  EXPECT_GE(closest, 0.99 * kGap);
}

TEST(FemContactNeighbours, VertexSlidAlongItsSheetIsLeftOnIt) {
  const BodiesModel m = sheet();
  SurfaceContact contact(m, settings());
  // A top node of the middle column slid along the top to half a gap from its neighbour one
  // cell to the left: within the gap of that neighbour's faces, in their plane.
  const int p = node_at(m, (kNx / 2) * kCell, kThick, 2 * kCell);
  ASSERT_GE(p, 0);
  const std::vector<Vec3> x_old = m.x0;
  std::vector<Vec3> x = m.x0;
  x[p].x -= Real(kCell - 0.5 * kGap);
  const Vec3 slid = x[p];
  std::vector<Vec3> v(x.size());
  std::vector<std::uint8_t> moved;
  const ContactStats st = contact.resolve(x_old, x, v, 1e-3, moved);
  std::printf("[ measured ] slid vertex: %d pairs, moved %.3g gaps\n", st.pairs,
              double(norm(x[p] - slid)) / kGap);
  EXPECT_EQ(st.pairs, 0);
  EXPECT_EQ(double(norm(x[p] - slid)), 0.0);
}

// A body shaped like a C lying on its side: two slabs kThick high, a slot of two gaps between
// them, joined by the first column of cells (the slot's side of a scanned bunny's lip).
BodiesModel slotted(double slot) {
  TetMesh box = make_box(Vec3d(0, 0, 0), Vec3d(kNx * kCell, 3 * kThick, kNz * kCell), kNx, 3, kNz);
  for (Vec3d& p : box.x)  // layers at 0, T, T + slot, 2 T + slot
    if (p.y > 1.5 * kThick) p.y += slot - kThick;
  std::vector<Tet> kept;
  for (const Tet& t : box.tets) {
    Vec3d c;
    for (int v : t.v) c += box.x[v] * 0.25;
    if (c.y > kThick && c.y < kThick + slot && c.x > kCell) continue;  // the slot
    kept.push_back(t);
  }
  box.tets = kept;
  FemSettings set;
  Material mat;
  mat.young = 1e4;
  return compile_bodies({compile_body(box, mat)}, set);
}

TEST(FemContactNeighbours, CreviceClosingKeepsItsSidesApart) {
  const double slot = 2 * kGap;  // within three gaps: neighbours of either radius
  const BodiesModel m = slotted(slot);
  SurfaceContact contact(m, settings());
  std::vector<Vec3> v(m.x0.size());
  std::vector<std::uint8_t> moved;
  std::vector<Vec3> x = m.x0;
  const ContactStats rest = contact.resolve(m.x0, x, v, 1e-3, moved);
  EXPECT_EQ(rest.pairs, 0) << "nothing is pushed at rest";
  // The upper slab's free end pressed down by 1.5 slots in one step (its nodes past the
  // second column; the second column half as far): it would end a gap through the lower slab.
  std::vector<int> upper, lower;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double px = double(m.x0[i].x), py = double(m.x0[i].y);
    if (py > kThick + 0.5 * slot) {
      x[i].y -= Real(1.5 * slot * std::min(1.0, std::max(0.0, px / kCell - 1)));
      if (std::fabs(py - kThick - slot) < 1e-9 && px > 2 * kCell) upper.push_back(int(i));
    } else if (std::fabs(py - kThick) < 1e-9 && px > 2 * kCell) {
      lower.push_back(int(i));
    }
  }
  const ContactStats st = contact.resolve(m.x0, x, v, 1e-3, moved);
  double closest = 1e9;  // the slot's sides, node over node
  for (int a : upper)
    for (int b : lower)
      if (std::fabs(double(m.x0[a].x - m.x0[b].x)) < 1e-9 &&
          std::fabs(double(m.x0[a].z - m.x0[b].z)) < 1e-9)
        closest = std::min(closest, double(x[a].y - x[b].y));
  const long crossed = intersecting_pairs(m, x);
  std::printf(
      "[ measured ] crevice: %d pairs, its sides %.3g gaps apart, %ld triangle pairs crossed\n",
      st.pairs, closest / kGap, crossed);
  EXPECT_GT(st.pairs, 0);
  EXPECT_EQ(crossed, 0);
  EXPECT_GE(closest, 0.99 * kGap) << "half the slot's rest width is kept";
}

}  // namespace
}  // namespace sphfem
