// The momentum exchange of the ray-traced coupling at one face (paper §4, with DESIGN.md
// corrections 1 and 2), written once for host and device.
//
// A face meets the K particles whose rays hit it, as one lump: mass M = sum m_k, velocity
// v_p = sum m_k v_k / M, hit point at the mass-weighted mean barycentric weights W. The face's
// velocity there is v_f = sum_j W_j v_j, and an impulse J applied at that point (node j gets
// W_j J) changes it by J / m_f with 1 / m_f = sum_j W_j^2 / m_j: the effective mass of the
// lumped nodes at the hit point. The particles get -J, so the relative velocity
// dv = v_f - v_p (eq. 12) changes by J (1/m_f + 1/M). Choosing J so that it reaches the
// target dv+ = -C_r dv_n + C_s dv_t (eqs. 10, 11 with the slip sign corrected) gives
//   J = (dv+ - dv) / (1/m_f + 1/M) = -(1 + C_r) mu dv_n - (1 - C_s) mu dv_t,
// mu = 1 / (1/m_f + 1/M). Momentum is conserved exactly whatever m_f is (+J and -J); with this
// m_f a single particle on a free triangle keeps kinetic energy at C_r = C_s = 1 wherever it
// hits, and with K = 1 the particle's velocity is eq. 14 with C = C_r (normal) and
// C = -C_s (tangential). The paper's m_face = mean(m_j) is right only at a vertex of a
// triangle with equal node masses; at the centre it overstates the face's inertia threefold.
#pragma once

#include "sphfem/core/vec.h"

namespace sphfem {

// Restitution and slip of one body's surface against the fluid, each in [0, 1].
struct ContactCoeffs {
  Real restitution = 0;  // C_r: dv+_n = -C_r dv_n; 1 elastic bounce, 0 the normal motion stops
  Real slip = 1;         // C_s: dv+_t = +C_s dv_t; 1 free slip, 0 no slip
};

namespace couple {

// Unit normal of the triangle (counter-clockwise seen from its front); zero if degenerate.
SPHFEM_HD Vec3 face_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = cross(b - a, c - a);
  const Real l = norm(n);
  return l > Real(0) ? n / l : Vec3();
}

// 1 / m_f at the point with barycentric weights w, from the nodes' inverse masses (0 for
// pinned nodes and static colliders).
SPHFEM_HD Real face_inverse_mass(const Real w[3], const Real inv_m[3]) {
  return w[0] * w[0] * inv_m[0] + w[1] * w[1] * inv_m[1] + w[2] * w[2] * inv_m[2];
}

// Impulse J on the face (the particles receive -J). n: unit normal pointing to the particles'
// side. Only an approaching contact, (v_face - v_particles) . n > 0, exchanges impulse; none
// when both sides are immovable.
SPHFEM_HD Vec3 contact_impulse(const Vec3& n, const Vec3& v_face, Real inv_m_face,
                               const Vec3& v_particles, Real inv_m_particles,
                               const ContactCoeffs& c) {
  const Vec3 dv = v_face - v_particles;
  const Real dn = dot(dv, n);
  const Real w = inv_m_face + inv_m_particles;
  if (!(dn > Real(0)) || !(w > Real(0))) return Vec3();
  const Vec3 dv_n = n * dn;
  const Vec3 dv_t = dv - dv_n;
  const Vec3 change = dv_n * (-(Real(1) + c.restitution)) - dv_t * (Real(1) - c.slip);
  return change / w;
}

// Paper eq. 6 with a skin: the share of a relative displacement of length `length` a particle
// may travel when its ray hits at distance t, stopping `skin` short of the surface.
SPHFEM_HD Real travel_fraction(Real t, Real length, Real skin) {
  if (!(length > Real(0))) return Real(1);
  const Real s = (t - skin) / length;
  return s < Real(0) ? Real(0) : (s > Real(1) ? Real(1) : s);
}

}  // namespace couple
}  // namespace sphfem
