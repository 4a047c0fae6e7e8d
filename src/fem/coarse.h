// A coarse level for the bodies' CG (host only): the nodes binned into aggregates a few
// elements across, each moving rigidly (three translations, three small rotations about its
// centroid), and the step operator A projected on them, P^T A P, a sparse matrix of 6x6 blocks
// (one per pair of patches that share an element), factored by a sparse Cholesky. Added
// to block Jacobi (z = D^-1 r + P (P^T A P)^-1 P^T r, a two-level additive Schwarz method), it
// carries the smooth, long-wave part of the error that block Jacobi moves a node ring per
// iteration, so the iterations no longer grow with the stiffness (docs/design.md, "Coarse
// level").
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/fem/model.h"

namespace sphfem {
namespace fem {

class CoarseLevel {
 public:
  // Aggregates of 3 median rest edges a side, refactored every 10 steps: with the sparse factor
  // 3 edges take fewer iterations than 4 for less time (2.5 and 2 only grow the factor), and
  // factoring once a step took 40 % of the step (docs/design.md, "Coarse level").
  static constexpr double kCells = 3.0;
  static constexpr int kEvery = 10;

  // Aggregates of the model's free nodes: cubes of side `cells` median rest edges, per body.
  CoarseLevel(const BodiesModel& m, double cells);
  ~CoarseLevel();

  // P^T A P at positions x for A = M (1 + dt alpha) + dt (dt + beta) K_R, the element part from
  // the rotated gradients P (3 per element) as the solver's element_stiffness, and its factor.
  // held (may be null): the components the walls held in the last solve (wall mask bits),
  // taken out of the modes, so that P^T A P is the operator of the filtered CG.
  void factor(const std::vector<Tet>& tets, const Vec3* x, const Vec3* grad, const Real* mu_vol,
              const Real* lambda_vol, const Real* beta, const Real* mass, const Real* alpha,
              Real dt, const std::uint8_t* held);

  // z += w (and p += w when p is not null), w = P (P^T A P)^-1 P^T r with the held components
  // (mask, may be null) taken out of w; returns r . w.
  double add(const Vec3* r, Vec3* z, Vec3* p, const std::uint8_t* mask);

  int size() const { return 6 * aggregates_; }

 private:
  Vec3 mode(int i, int k) const;  // mode k of node i's aggregate at node i

  int nodes_ = 0, aggregates_ = 0;
  std::vector<int> agg_;                 // each node's aggregate, -1 for pinned nodes
  std::vector<int> tet_start_, tet_of_;  // each aggregate's elements: the assembly's rows
  std::vector<Vec3> centre_;             // each aggregate's centroid at the last factor
  std::vector<Vec3> at_;                 // the node positions at the last factor
  std::vector<std::uint8_t> held_;       // the wall mask at the last factor
  Real scale_ = 1;                       // 1 / the aggregates' side: rotations as displacements
  std::vector<double> y_, c_;
  struct Factor;
  std::unique_ptr<Factor> f_;
};

}  // namespace fem
}  // namespace sphfem
