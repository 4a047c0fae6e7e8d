// The coupling stages, written once for every backend (CpuExec, CudaExec): per-particle and
// per-face bodies are host-and-device lambdas over raw arrays in small views copied by value.
// The momentum exchange itself, all contacts of a step solved together, is in
// couple/contact_solve.h.
#pragma once

#include <cstdint>

#include "sphfem/couple/impulse.h"
#include "sphfem/fem/mesh.h"

namespace sphfem::couple {

constexpr int kMaxSets = 4;

// One set of triangles and its nodes (CoupleSurface without the host-side tables).
struct SurfaceView {
  int first = 0, triangles = 0;  // global index of the first triangle, count
  int node_base = 0;             // global index of the first node (the contact solve's)
  const Tri* tri = nullptr;
  const Vec3* x = nullptr;
  const Vec3* v = nullptr;
  const Real* mass = nullptr;
  const std::uint8_t* pinned = nullptr;
  Vec3* impulse = nullptr;
};

struct SurfacesView {
  int count = 0, faces = 0, bodies = 0, nodes = 0;
  SurfaceView set[kMaxSets];
  const int* body_first = nullptr;  // bodies + 1 entries: global first face of each body
  const ContactCoeffs* coeffs = nullptr;
};

struct HitView {
  const int* face = nullptr;
  const Real* t = nullptr;
  const Real* u = nullptr;
  const Real* v = nullptr;
  const Real* bias = nullptr;  // HitArrays::bias
};

struct ParticleView {
  int n = 0;
  const Vec3* x = nullptr;
  Vec3* v = nullptr;
  Real mass = 0;
};

// The three nodes of face f: index, position, velocity and inverse mass (0: infinite).
// node[] is the set's own index; the global one is node_base + node[].
struct FaceNodes {
  int set = -1;
  int node[3] = {0, 0, 0};
  Vec3 x[3], v[3];
  Real inv_m[3] = {0, 0, 0};
};

SPHFEM_HD FaceNodes face_nodes(const SurfacesView& S, int f) {
  FaceNodes fn;
  int s = 0;
  while (s + 1 < S.count && f >= S.set[s + 1].first) ++s;
  const SurfaceView& sv = S.set[s];
  const Tri tri = sv.tri[f - sv.first];
  fn.set = s;
  for (int k = 0; k < 3; ++k) {
    const int j = tri.v[k];
    fn.node[k] = j;
    fn.x[k] = sv.x[j];
    fn.v[k] = sv.v ? sv.v[j] : Vec3();
    const bool free = sv.mass && !(sv.pinned && sv.pinned[j]) && sv.mass[j] > Real(0);
    fn.inv_m[k] = free ? Real(1) / sv.mass[j] : Real(0);
  }
  return fn;
}

// The body owning global face f (binary search over the bodies' first faces).
SPHFEM_HD int body_of(const SurfacesView& S, int f) {
  int lo = 0, hi = S.bodies;  // body_first[lo] <= f < body_first[hi]
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    if (S.body_first[mid] <= f)
      lo = mid;
    else
      hi = mid;
  }
  return lo;
}

SPHFEM_HD void weights(const HitView& h, int i, Real w[3]) {
  w[1] = h.u[i];
  w[2] = h.v[i];
  w[0] = Real(1) - w[1] - w[2];
}

SPHFEM_HD Vec3 at(const Vec3 p[3], const Real w[3]) {
  return p[0] * w[0] + p[1] * w[1] + p[2] * w[2];
}

// Eq. 6 for every particle: travel fraction and the velocity of the surface at its hit.
template <class Exec>
void travel(Exec& ex, const SurfacesView S, const HitView h, const ParticleView p, Real skin,
            Real dt, Real* travel, Vec3* surface_v) {
  parallel_for(ex, p.n, [=] SPHFEM_LAMBDA(int i) {
    const int f = h.face[i];
    if (f < 0 || f >= S.faces) {
      travel[i] = Real(1);
      surface_v[i] = Vec3();
      return;
    }
    const FaceNodes fn = face_nodes(S, f);
    Real w[3];
    weights(h, i, w);
    const Vec3 vs = at(fn.v, w);
    travel[i] = travel_fraction(h.t[i], norm(p.v[i] - vs) * dt, skin);
    surface_v[i] = vs;
  });
}

// After the drift: a particle that hit a face is put back at least `skin` in front of the
// face's plane, on the side it came from (against its motion relative to the face). Eq. 6
// keeps the skin along the ray only, so a grazing particle can end within round-off of the
// plane, and the next step's ray would start behind it. Positions only: no momentum changes.
template <class Exec>
void push_out(Exec& ex, const SurfacesView S, const HitView h, int n, Vec3* x, const Vec3* v,
              Real skin) {
  parallel_for(ex, n, [=] SPHFEM_LAMBDA(int i) {
    const int f = h.face[i];
    if (f < 0 || f >= S.faces) return;
    const FaceNodes fn = face_nodes(S, f);
    Real w[3];
    weights(h, i, w);
    const Vec3 nrm = face_normal(fn.x[0], fn.x[1], fn.x[2]);
    const Real approach = dot(v[i] - at(fn.v, w), nrm);
    if (approach == Real(0)) return;
    const Real side = approach < Real(0) ? Real(1) : Real(-1);
    const Real d = side * dot(x[i] - at(fn.x, w), nrm);
    if (d < skin) x[i] += nrm * (side * (skin - d));
  });
}

// flag[i] = 1 for a particle with a hit; returns the number of face indices out of range.
template <class Exec>
int flag_hits(Exec& ex, const HitView h, int n, int faces, std::uint32_t* flag) {
  const double bad = reduce_sum(ex, n, [=] SPHFEM_LAMBDA(int i) -> double {
    const int f = h.face[i];
    flag[i] = f >= 0 && f < faces ? 1u : 0u;
    return f >= faces ? 1.0 : 0.0;
  });
  return int(bad + 0.5);
}

}  // namespace sphfem::couple
