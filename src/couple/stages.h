// The coupling stages, written once for every backend (CpuExec, CudaExec): per-particle and
// per-face bodies are host-and-device lambdas over raw arrays in small views copied by value.
// Grouping by face follows paper §4.3: compact the hits into (key, particle) pairs, radix-sort
// them by key, find the first pair of each key by a scan; one thread per key then does the
// face's exchange (couple/impulse.h).
#pragma once

#include <cstdint>

#include "sphfem/couple/impulse.h"
#include "sphfem/fem/mesh.h"

namespace sphfem::couple {

constexpr int kMaxSets = 4;

// One set of triangles and its nodes (CoupleSurface without the host-side tables).
struct SurfaceView {
  int first = 0, triangles = 0;  // global index of the first triangle, count
  const Tri* tri = nullptr;
  const Vec3* x = nullptr;
  const Vec3* v = nullptr;
  const Real* mass = nullptr;
  const std::uint8_t* pinned = nullptr;
  Vec3* impulse = nullptr;
};

struct SurfacesView {
  int count = 0, faces = 0, bodies = 0;
  SurfaceView set[kMaxSets];
  const int* body_first = nullptr;  // bodies + 1 entries: global first face of each body
  const ContactCoeffs* coeffs = nullptr;
};

struct HitView {
  const int* face = nullptr;
  const Real* t = nullptr;
  const Real* u = nullptr;
  const Real* v = nullptr;
};

struct ParticleView {
  int n = 0;
  const Vec3* x = nullptr;
  Vec3* v = nullptr;
  Real mass = 0;
};

// The three nodes of face f: index, position, velocity and inverse mass (0: infinite).
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

// Pair k = offset[i] of particle i: key 2 f + side (side 1 = behind the face's front), value i.
// The side is where the particle is against the plane; on the plane, the side it comes from.
template <class Exec>
void make_pairs(Exec& ex, const SurfacesView S, const HitView h, const ParticleView p,
                const std::uint32_t* offset, std::uint32_t* keys, std::uint32_t* vals) {
  parallel_for(ex, p.n, [=] SPHFEM_LAMBDA(int i) {
    const int f = h.face[i];
    if (f < 0 || f >= S.faces) return;
    const FaceNodes fn = face_nodes(S, f);
    Real w[3];
    weights(h, i, w);
    const Vec3 n = face_normal(fn.x[0], fn.x[1], fn.x[2]);
    Real s = dot(p.x[i] - at(fn.x, w), n);
    if (s == Real(0)) s = -dot(p.v[i] - at(fn.v, w), n);
    const std::uint32_t k = offset[i];
    keys[k] = 2u * std::uint32_t(f) + (s < Real(0) ? 1u : 0u);
    vals[k] = std::uint32_t(i);
  });
}

// head[k] = 1 where a run of equal keys starts.
template <class Exec>
void run_heads(Exec& ex, const std::uint32_t* keys, int m, std::uint32_t* head) {
  parallel_for(ex, m,
               [=] SPHFEM_LAMBDA(int k) { head[k] = k == 0 || keys[k] != keys[k - 1] ? 1u : 0u; });
}

// first[r] = index of run r's first pair (index = exclusive scan of the heads); first[runs] = m.
template <class Exec>
void run_starts(Exec& ex, const std::uint32_t* keys, const std::uint32_t* index, int m, int runs,
                std::uint32_t* first) {
  parallel_for(ex, m, [=] SPHFEM_LAMBDA(int k) {
    if (k == 0 || keys[k] != keys[k - 1]) first[index[k]] = std::uint32_t(k);
    if (k == m - 1) first[runs] = std::uint32_t(m);
  });
}

// What one run did, for the statistics.
struct RunResult {
  Vec3 impulse;  // on the face
  int body = 0;
  int new_face = 0;   // first run of its face (the other side may follow)
  int exchanged = 0;  // approaching: an impulse was exchanged
  // What the face's nodes receive (set -1: nothing), summed into them afterwards in a fixed
  // order (core/node_sums.h) rather than by atomics: a node is shared by several faces.
  int set = -1;
  int node[3] = {0, 0, 0};
  Vec3 node_impulse[3];
};

// One thread per (face, side): the particles there as one lump (mass-weighted velocity and
// hit weights), the face impulse J (impulse.h); -J to the particles by mass share (each has
// one hit, so plain writes); +J by the lump's weights is recorded for the face's nodes.
template <class Exec>
void exchange(Exec& ex, const SurfacesView S, const HitView h, const ParticleView p,
              const std::uint32_t* keys, const std::uint32_t* vals, const std::uint32_t* first,
              int runs, RunResult* out) {
  parallel_for(ex, runs, [=] SPHFEM_LAMBDA(int r) {
    const std::uint32_t b = first[r], e = first[r + 1];
    const std::uint32_t key = keys[b];
    const int f = int(key >> 1);
    const FaceNodes fn = face_nodes(S, f);
    Vec3 n = face_normal(fn.x[0], fn.x[1], fn.x[2]);
    if (key & 1u) n = -n;  // toward the particles
    // Equal particle masses: the mass-weighted means are plain means.
    Vec3 vp;
    Real wm[3] = {0, 0, 0};
    for (std::uint32_t k = b; k < e; ++k) {
      const int i = int(vals[k]);
      Real w[3];
      weights(h, i, w);
      vp += p.v[i];
      for (int c = 0; c < 3; ++c) wm[c] += w[c];
    }
    const Real inv_count = Real(1) / Real(e - b);
    vp *= inv_count;
    for (int c = 0; c < 3; ++c) wm[c] *= inv_count;
    const Real inv_mp = inv_count / p.mass;
    const Real inv_mf = face_inverse_mass(wm, fn.inv_m);
    const int body = body_of(S, f);
    const Vec3 J = contact_impulse(n, at(fn.v, wm), inv_mf, vp, inv_mp, S.coeffs[body]);
    RunResult res;
    res.impulse = J;
    res.body = body;
    res.new_face = r == 0 || (keys[first[r - 1]] >> 1) != key >> 1 ? 1 : 0;
    res.exchanged = J.x != Real(0) || J.y != Real(0) || J.z != Real(0) ? 1 : 0;
    if (res.exchanged) {
      const Vec3 dv = J * inv_mp;
      for (std::uint32_t k = b; k < e; ++k) p.v[vals[k]] -= dv;
      if (S.set[fn.set].impulse) {
        res.set = fn.set;
        for (int c = 0; c < 3; ++c) {
          res.node[c] = fn.node[c];
          res.node_impulse[c] = J * wm[c];
        }
      }
    }
    out[r] = res;
  });
}

}  // namespace sphfem::couple
