// Host-side front end to the BVH on any backend: positions, triangles and queries as host
// vectors, copied to the backend's memory and back. For tools, metrics (e.g. counting
// particles inside closed bodies) and for comparing backends in tests; code that already
// holds its data on the backend uses SurfaceBvh and the batch queries (bvh.h) directly.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "sphfem/collide/bvh.h"
#include "sphfem/core/backend.h"

namespace sphfem {

class Collider {
 public:
  virtual ~Collider() = default;

  // Copies the triangles and positions and builds the tree.
  virtual void build(const std::vector<Vec3>& x, const std::vector<Tri>& tris,
                     BvhBuild method = BvhBuild::Auto) = 0;
  // New positions (same triangles): static queries then use x.
  virtual void refit(const std::vector<Vec3>& x) = 0;
  // A step from x_old to x_new: moving queries use both, static queries x_new.
  virtual void refit(const std::vector<Vec3>& x_old, const std::vector<Vec3>& x_new) = 0;
  // A new tree over the same triangles at the current positions.
  virtual void rebuild(BvhBuild method = BvhBuild::Auto) = 0;
  virtual double quality() = 0;
  virtual int depth() const = 0;

  // tmax empty: unbounded.
  virtual std::vector<collide::RayHit> cast_rays(const std::vector<Vec3>& origin,
                                                 const std::vector<Vec3>& dir,
                                                 const std::vector<Real>& tmax) = 0;
  virtual std::vector<collide::SegmentHit> cast_moving(const std::vector<Vec3>& p,
                                                       const std::vector<Vec3>& vel, Real dt,
                                                       Real skin) = 0;
  // The earliest exact contact of each path from[i] -> to[i] with the faces moving from the
  // last refit's old positions to its new ones (collide::moving_contact).
  virtual std::vector<collide::ContactHit> contacts(const std::vector<Vec3>& from,
                                                    const std::vector<Vec3>& to, Real tol,
                                                    bool front_only = false) = 0;
  virtual std::vector<int> count_crossings(const std::vector<Vec3>& from,
                                           const std::vector<Vec3>& to) = 0;
  virtual std::vector<std::uint8_t> inside(const std::vector<Vec3>& p) = 0;
  virtual std::vector<collide::ClosestHit> closest(const std::vector<Vec3>& p, Real radius) = 0;
};

// Throws std::runtime_error when the backend is not usable here (e.g. CUDA without a GPU).
std::unique_ptr<Collider> make_collider(Backend backend);

}  // namespace sphfem
