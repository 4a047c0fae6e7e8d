// The tank's walls as constraints of the implicit step (Baraff & Witkin 1998, "Large steps in
// cloth simulation", §5.3): a node that would leave the box within the step has that velocity
// component fixed so that it ends the step on the wall, and the filtered CG (stages.h) solves
// for the other components with the node's elements feeling the wall. A wall that would have
// to pull lets go. Mask bit c (1, 2, 4): axis c is held; bit 3 + c: at the upper wall.
#pragma once

#include "fem/stages.h"

namespace sphfem::fem {

struct WallBox {
  Vec3 lo, hi;
  Real touch;  // m, a node this close to a wall at the step's start rests on it
};

// The velocity change that puts node i on the wall of axis c at the step's end.
SPHFEM_HD Real onto_wall(Real wall, Real x, Real v, Real dt) { return (wall - x) / dt - v; }

// Marks and targets. First pass (f null): every axis of a node that rests on a wall or would
// leave the box with the velocity change dv is held. Later passes (f = A dv - b, the force the
// walls supply): holds that pull are dropped, axes that would now leave the box are added.
// Held components of dv are set to their targets; a dropped one keeps its target until the
// step is solved again. Returns how many nodes gained a held axis.
template <class Exec>
int hold_walls(Exec& ex, const NodeView nv, const Vec3* x, const Vec3* v, const Vec3* f, WallBox w,
               Real dt, std::uint8_t* mask, Vec3* dv) {
  const double changed = reduce_sum(ex, nv.n, [=] SPHFEM_LAMBDA(int i) -> double {
    if (nv.pinned[i]) {
      mask[i] = 0;
      return 0.0;
    }
    const std::uint8_t m0 = f ? mask[i] : std::uint8_t(0);
    std::uint8_t m = m0;
    Vec3 d = dv[i];
    const Vec3 xi = x[i], vi = v[i];
    for (int c = 0; c < 3; ++c) {
      const std::uint8_t held = std::uint8_t(1u << c), upper = std::uint8_t(8u << c);
      if ((m & held) && f) {
        const Real push = (m & upper) ? -f[i][c] : f[i][c];
        if (push < Real(0)) {
          m = std::uint8_t(m & ~(held | upper));
          continue;
        }
      }
      if (!(m & held)) {
        const Real end = xi[c] + dt * (vi[c] + d[c]);
        if (end < w.lo[c] || (!f && xi[c] <= w.lo[c] + w.touch && end <= xi[c]))
          m = std::uint8_t(m | held);
        else if (end > w.hi[c] || (!f && xi[c] >= w.hi[c] - w.touch && end >= xi[c]))
          m = std::uint8_t(m | held | upper);
      }
      if (m & held) d[c] = onto_wall((m & upper) ? w.hi[c] : w.lo[c], xi[c], vi[c], dt);
    }
    mask[i] = m;
    dv[i] = d;
    return (m & ~m0 & 7) ? 1.0 : 0.0;
  });
  return int(changed + 0.5);
}

// f = q - b (the walls' force, N s over the step, from q = A dv).
template <class Exec>
void wall_force(Exec& ex, int n, const Vec3* q, const Vec3* b, Vec3* f) {
  parallel_for_light(ex, n, [=] SPHFEM_LAMBDA(int i) { f[i] = q[i] - b[i]; });
}

// Coulomb friction of the held nodes as impulses in the step's right-hand side b, so that
// the whole body feels them within the step (applied to each node after the step instead,
// a stiff tube sliding on the floor sheared by 7 mm as its nodes stopped one by one): each
// held node's motion along the walls (the free components of v + dv) is opposed by at most
// mu times its normal impulse f, and by no more than would stop it were it free. fr holds the
// friction b already has (zero at the step's start); it is replaced. Returns the number of
// held nodes.
template <class Exec>
int wall_friction(Exec& ex, const NodeView nv, const std::uint8_t* mask, const Vec3* f,
                  const Vec3* v, const Vec3* dv, Real mu, Vec3* fr, Vec3* b) {
  const double held = reduce_sum(ex, nv.n, [=] SPHFEM_LAMBDA(int i) -> double {
    const std::uint8_t m = mask[i];
    Vec3 j;
    if ((m & 7) && !nv.pinned[i]) {
      Real normal = 0;
      for (int c = 0; c < 3; ++c)
        if (m & (1u << c)) normal += f[i][c] < Real(0) ? -f[i][c] : f[i][c];
      const Vec3 slide = free_part(v[i] + dv[i], m);  // the motion along the walls
      const Real s = norm(slide);
      if (s > Real(0)) {
        const Real stop = nv.mass[i] * s, limit = mu * normal;
        j = slide * (-(limit < stop ? limit : stop) / s);
      }
    }
    b[i] += j - fr[i];
    fr[i] = j;
    return (m & 7) && !nv.pinned[i] ? 1.0 : 0.0;
  });
  return int(held + 0.5);
}

}  // namespace sphfem::fem
