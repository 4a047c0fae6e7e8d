// Bounding volume hierarchy over a triangle soup whose vertices move every step, and the
// batch queries the coupling needs: nearest hit of rays, the moving-segment query of
// particles against moving faces, crossing counts (inside tests by parity) and closest points.
//
// Why our own BVH and not Embree: the same traversal has to run inside CUDA kernels (no
// OptiX here, no RT cores on H100/H200), the positions change every step so the tree is
// refit in O(n) rather than rebuilt, and the moving-segment query needs boxes swept over a
// step. One node layout and one traversal (traverse.h) serve both backends; measured numbers
// are in docs/design.md.
//
// Builds: binned SAH top-down on the host (the default on the CPU: shallower, tighter trees)
// or an LBVH over 30-bit Morton codes with Karras' (2012) parallel hierarchy (the default on
// CUDA, also runnable on the CPU). Refit is bottom-up with one atomic flag per node: the
// second child to arrive computes its parent. quality() compares the sum of internal box
// areas with its value right after the build; rebuild when it passes about 2.
//
// Memory: all arrays live in Exec's memory space (device memory for CudaExec); the caller's
// positions and triangles must too, and the triangle array must outlive the BVH.
#pragma once

#include <cstdint>

#include "sphfem/collide/traverse.h"
#include "sphfem/core/memory.h"
#include "sphfem/fem/mesh.h"

namespace sphfem {

enum class BvhBuild {
  Auto,  // Sah on the CPU, Lbvh on CUDA
  Sah,   // binned SAH on the host (device data is copied over and back)
  Lbvh   // Morton codes + Karras hierarchy on the backend itself
};

template <class Exec>
class SurfaceBvh {
 public:
  SurfaceBvh();

  // Builds the tree over triangles tris[0 .. ntris-1] at positions x, and the surface
  // topology (edge neighbours, vertex fans) that closest-point signs use.
  void build(Exec& ex, const Vec3* x, const Tri* tris, int ntris, BvhBuild method = BvhBuild::Auto);
  // A new tree over the same triangles at positions x (when quality() has degraded); keeps
  // the topology.
  void rebuild(Exec& ex, const Vec3* x, BvhBuild method = BvhBuild::Auto);
  // Box update for positions x (same triangles, same tree).
  void refit(Exec& ex, const Vec3* x);
  // Box update over a step from x_old to x_new: leaf boxes hold both positions, grown by the
  // faces' sweep deviation; needed by moving_nearest / cast_moving, and valid for static
  // queries at either position.
  void refit(Exec& ex, const Vec3* x_old, const Vec3* x_new);
  // Sum of internal-node box areas now over the same sum right after the last build (1 when
  // nothing moved; rebuild above ~2). 1 for trees without internal nodes.
  double quality(Exec& ex);

  collide::BvhView view() const;
  int triangles() const { return ntris_; }
  int node_count() const { return nnodes_; }
  int depth() const { return depth_; }
  BvhBuild method() const { return method_; }

 private:
  void derive_topology(Exec& ex, const Tri* tris, int ntris);
  void build_sah(Exec& ex, const Vec3* x);
  void build_lbvh(Exec& ex, const Vec3* x);
  void finish_build(Exec& ex, const Vec3* x);

  const Tri* tris_ = nullptr;
  int ntris_ = 0, nnodes_ = 0, nleaves_ = 0, depth_ = 0, nverts_ = 0;
  double area0_ = 0;
  BvhBuild method_ = BvhBuild::Auto;
  Buffer<collide::BvhNode> nodes_;
  Buffer<int> parent_, leaves_, prims_, flags_;
  Buffer<int> nbr_, vstart_, vfaces_;
  Buffer<std::uint32_t> keys_, vals_;
};

// Per-query outputs in Exec's memory space; optional arrays may be null.
struct RayHits {
  int* face = nullptr;  // -1: no hit
  Real* t = nullptr;
  Real* u = nullptr;  // barycentric weights of the face's second and third vertex
  Real* v = nullptr;
};

struct SegmentHits {
  int* face = nullptr;  // -1: no hit
  Real* t = nullptr;    // distance along the relative motion to the face's old position
  Real* u = nullptr;
  Real* v = nullptr;
  Real* len = nullptr;  // optional: length of the relative motion over the step
  Vec3* rel = nullptr;  // optional: the relative motion (particle minus face) over the step
};

struct ContactHits {
  int* face = nullptr;  // -1: no contact
  Real* tau = nullptr;  // time of the contact within the step, in (0, 1]
  Real* u = nullptr;    // barycentric weights of the face's second and third vertex there
  Real* v = nullptr;
  int* side = nullptr;  // the particle's side before it: +1 in front of the face, -1 behind
};

struct ClosestHits {
  int* face = nullptr;  // -1: nothing within the radius
  Real* dist = nullptr;
  Vec3* point = nullptr;  // optional
  int* side = nullptr;    // optional: +1 outside, -1 inside, 0 on the surface
  Real* u = nullptr;      // optional: barycentric weights of the face's second and third
  Real* v = nullptr;      // vertex at the closest point
};

// Nearest hit of origin[i] + t dir[i], t in [0, tmax[i]] (tmax null: unbounded), at
// positions x (which the BVH's boxes must bound).
template <class Exec>
void cast_rays(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x, int n, const Vec3* origin,
               const Vec3* dir, const Real* tmax, RayHits out);

// Particles p[i] moving with velocity vel[i] over dt against faces moving from x_old to x_new
// (bvh refit with refit(ex, x_old, x_new)); skin extends every cast. Earliest hit per
// particle, by the time t / len within the step. Reported face ids are the BVH's plus
// face_offset. With merge, a particle's entry is only replaced by an earlier hit (out.len is
// then required): one call per triangle set (bodies, static colliders) gives the earliest
// hit over all sets in the numbering "set k's face i = faces of sets 0..k-1 + i". With
// front_only, faces a particle starts behind are skipped (collide::moving_nearest).
template <class Exec>
void cast_moving(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x_old, const Vec3* x_new, int n,
                 const Vec3* p, const Vec3* vel, Real dt, Real skin, SegmentHits out,
                 int face_offset = 0, bool merge = false, bool front_only = false);

// The earliest exact contact (within tol) of each particle's straight path from[i] -> to[i]
// over a step with the faces moving linearly from x_old to x_new (bvh refit with
// refit(ex, x_old, x_new)): collide::moving_contact, front_only as there.
template <class Exec>
void cast_contacts(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x_old, const Vec3* x_new,
                   int n, const Vec3* from, const Vec3* to, Real tol, ContactHits out,
                   bool front_only = false);

// Number of faces the segment from[i] -> to[i] crosses.
template <class Exec>
void count_crossings(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x, int n, const Vec3* from,
                     const Vec3* to, int* count);

// 1 where p[i] is inside the closed surfaces at x (odd number of crossings of a ray to
// infinity), else 0.
template <class Exec>
void inside_closed(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x, int n, const Vec3* p,
                   std::uint8_t* inside);

// Closest surface point to p[i] within radius.
template <class Exec>
void closest_points(Exec& ex, const SurfaceBvh<Exec>& bvh, const Vec3* x, int n, const Vec3* p,
                    Real radius, ClosestHits out);

}  // namespace sphfem
