#include "fem/coarse.h"

// Serial: Eigen's OpenMP products block by the thread count, which would change the bits.
#define EIGEN_DONT_PARALLELIZE
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>

#include "fem/corotated.h"
#include "fem/stages.h"  // free_part

namespace sphfem {
namespace fem {

// P^T A P is sparse: a patch meets only the patches it shares an element with (about 15 on a
// graded mesh). Stored as 6x6 blocks per pair of patches, factored by a sparse Cholesky in a
// fill-reducing order of the patches: the dense factor of the bench's bunny (915 unknowns)
// read 6.7 MB twice per CG iteration and took 0.3 G flops to refactor (docs/design.md, "Coarse
// level"). Ordering patches, not unknowns, keeps each patch's six together, so the factor is
// made of dense 6x6 blocks and is solved block by block (`solve`): Eigen's scalar triangular
// solves took 2 ns an entry, most of the stiff bunny's step.
struct CoarseLevel::Factor {
  std::vector<int> start, col;  // blocks of patch g: its neighbours col[start[g]..start[g+1])
  std::vector<double> block;    // 36 per block, row-major: a(6 g + l, 6 h + k) at 6 l + k
  std::vector<int> order;       // each patch's place in the factor (AMD on the patch graph)
  // L by blocks, in the factor's order: block column J holds its diagonal block and then the
  // blocks below it, rows lrow[lstart[J]..lstart[J + 1]) (the first is J), 36 values each,
  // row-major.
  std::vector<int> lstart, lrow;
  std::vector<double> lval;
  std::vector<double> x;  // the solve's vector, in the factor's order
  bool ok = false;

  double* at(int g, int h) {
    const auto first = col.begin() + start[g], last = col.begin() + start[g + 1];
    return block.data() + 36 * (std::lower_bound(first, last, h) - col.begin());
  }
  void blocks_of_l(const Eigen::SparseMatrix<double>& L);
  void solve(const double* y, double* c);
};

// Copies Eigen's L into its 6x6 blocks (entries the pattern lacks stay 0).
void CoarseLevel::Factor::blocks_of_l(const Eigen::SparseMatrix<double>& L) {
  const int nb = int(L.cols()) / 6;
  lstart.assign(std::size_t(nb) + 1, 0);
  lrow.clear();
  std::vector<int> mark(std::size_t(nb), -1);
  for (int J = 0; J < nb; ++J) {
    lrow.push_back(J);
    mark[J] = J;
    for (int k = 0; k < 6; ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(L, 6 * J + k); it; ++it) {
        const int I = int(it.row()) / 6;
        if (mark[I] != J) mark[I] = J, lrow.push_back(I);
      }
    std::sort(lrow.begin() + lstart[J] + 1, lrow.end());
    lstart[J + 1] = int(lrow.size());
  }
  lval.assign(std::size_t(36) * lrow.size(), 0.0);
  for (int J = 0; J < nb; ++J)
    for (int k = 0; k < 6; ++k)
      for (Eigen::SparseMatrix<double>::InnerIterator it(L, 6 * J + k); it; ++it) {
        const int I = int(it.row()) / 6;
        const auto first = lrow.begin() + lstart[J], last = lrow.begin() + lstart[J + 1];
        const long b = std::lower_bound(first + 1, last, I) - lrow.begin();
        lval[std::size_t(36) * std::size_t(I == J ? lstart[J] : b) + 6 * (it.row() % 6) + k] =
            it.value();
      }
  x.assign(std::size_t(6) * nb, 0.0);
}

// c = (P^T A P)^-1 y: L x = y by block columns, then L^T c = x, in the factor's order.
void CoarseLevel::Factor::solve(const double* y, double* c) {
  const int nb = int(lstart.size()) - 1;
  for (int g = 0; g < nb; ++g)
    for (int k = 0; k < 6; ++k) x[6 * std::size_t(order[g]) + k] = y[6 * g + k];
  for (int J = 0; J < nb; ++J) {
    double* xj = x.data() + 6 * J;
    const double* d = lval.data() + std::size_t(36) * lstart[J];
    for (int l = 0; l < 6; ++l) {
      double s = xj[l];
      for (int k = 0; k < l; ++k) s -= d[6 * l + k] * xj[k];
      xj[l] = s / d[6 * l + l];
    }
    for (int e = lstart[J] + 1; e < lstart[J + 1]; ++e) {
      const double* b = lval.data() + std::size_t(36) * e;
      double* xi = x.data() + 6 * lrow[e];
      for (int l = 0; l < 6; ++l)
        xi[l] -= b[6 * l] * xj[0] + b[6 * l + 1] * xj[1] + b[6 * l + 2] * xj[2] +
                 b[6 * l + 3] * xj[3] + b[6 * l + 4] * xj[4] + b[6 * l + 5] * xj[5];
    }
  }
  for (int J = nb - 1; J >= 0; --J) {
    double s[6];
    double* xj = x.data() + 6 * J;
    for (int k = 0; k < 6; ++k) s[k] = xj[k];
    for (int e = lstart[J] + 1; e < lstart[J + 1]; ++e) {
      const double* b = lval.data() + std::size_t(36) * e;
      const double* xi = x.data() + 6 * lrow[e];
      for (int k = 0; k < 6; ++k)
        s[k] -= b[k] * xi[0] + b[6 + k] * xi[1] + b[12 + k] * xi[2] + b[18 + k] * xi[3] +
                b[24 + k] * xi[4] + b[30 + k] * xi[5];
    }
    const double* d = lval.data() + std::size_t(36) * lstart[J];
    for (int l = 5; l >= 0; --l) {
      double v = s[l];
      for (int k = l + 1; k < 6; ++k) v -= d[6 * k + l] * xj[k];
      xj[l] = v / d[6 * l + l];
    }
  }
  for (int g = 0; g < nb; ++g)
    for (int k = 0; k < 6; ++k) c[6 * g + k] = x[6 * std::size_t(order[g]) + k];
}

CoarseLevel::CoarseLevel(const BodiesModel& m, double cells) : f_(std::make_unique<Factor>()) {
  nodes_ = m.nodes;
  std::vector<Real> len;
  len.reserve(m.tets.size() * 6);
  for (const Tet& t : m.tets)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) len.push_back(norm(m.x0[t.v[a]] - m.x0[t.v[b]]));
  double side = 1;
  if (!len.empty()) {
    std::nth_element(len.begin(), len.begin() + len.size() / 2, len.end());
    side = cells * double(len[len.size() / 2]);
  }
  // Larger patches while the coarse level would pass its cap: its dense factor grows as the
  // square of its size, and its cost per step as the cube.
  std::map<std::tuple<int, long, long, long>, int> cell;  // (body, cube) -> aggregate
  for (;;) {
    cell.clear();
    aggregates_ = 0;
    agg_.assign(std::size_t(nodes_), -1);
    for (int b = 0; b + 1 < int(m.node_offset.size()); ++b)
      for (int i = m.node_offset[b]; i < m.node_offset[b + 1]; ++i) {
        if (m.pinned[i]) continue;
        const Vec3d p(m.x0[i]);
        const auto key =
            std::make_tuple(b, long(std::floor(p.x / side)), long(std::floor(p.y / side)),
                            long(std::floor(p.z / side)));
        auto it = cell.find(key);
        if (it == cell.end()) it = cell.emplace(key, aggregates_++).first;
        agg_[i] = it->second;
      }
    if (size() <= FemSettings::kCoarseMaxSize) break;
    side *= 1.25;
  }
  scale_ = Real(1.0 / side);
  centre_.assign(std::size_t(aggregates_), Vec3());
  at_.assign(std::size_t(nodes_), Vec3());
  held_.assign(std::size_t(nodes_), 0);
  y_.assign(std::size_t(size()), 0.0);
  c_.assign(std::size_t(size()), 0.0);
  // Which patches share an element: the blocks of P^T A P.
  std::vector<std::vector<int>> near(static_cast<std::size_t>(aggregates_));
  for (int g = 0; g < aggregates_; ++g) near[g].push_back(g);
  for (const Tet& t : m.tets)
    for (int a : t.v)
      for (int b : t.v)
        if (agg_[a] >= 0 && agg_[b] >= 0 && agg_[a] != agg_[b]) near[agg_[a]].push_back(agg_[b]);
  f_->start.assign(std::size_t(aggregates_) + 1, 0);
  for (int g = 0; g < aggregates_; ++g) {
    std::sort(near[g].begin(), near[g].end());
    near[g].erase(std::unique(near[g].begin(), near[g].end()), near[g].end());
    f_->start[g + 1] = f_->start[g] + int(near[g].size());
    f_->col.insert(f_->col.end(), near[g].begin(), near[g].end());
  }
  f_->block.assign(std::size_t(36) * f_->col.size(), 0.0);
  // Each patch's elements, in element order.
  tet_start_.assign(std::size_t(aggregates_) + 1, 0);
  auto each_patch = [&](const Tet& t, auto&& visit) {
    int seen[4], n = 0;
    for (int v : t.v)
      if (agg_[v] >= 0 && std::find(seen, seen + n, agg_[v]) == seen + n)
        visit(seen[n++] = agg_[v]);
  };
  for (const Tet& t : m.tets) each_patch(t, [&](int g) { ++tet_start_[g + 1]; });
  for (int g = 0; g < aggregates_; ++g) tet_start_[g + 1] += tet_start_[g];
  tet_of_.resize(std::size_t(tet_start_.back()));
  {
    std::vector<int> fill(tet_start_.begin(), tet_start_.end() - 1);
    for (std::size_t t = 0; t < m.tets.size(); ++t)
      each_patch(m.tets[t], [&](int g) { tet_of_[fill[g]++] = int(t); });
  }
  // A fill-reducing order of the patches, from their graph.
  Eigen::SparseMatrix<int> graph(aggregates_, aggregates_);
  std::vector<Eigen::Triplet<int>> links;
  links.reserve(f_->col.size());
  for (int g = 0; g < aggregates_; ++g)
    for (int e = f_->start[g]; e < f_->start[g + 1]; ++e) links.emplace_back(f_->col[e], g, 1);
  graph.setFromTriplets(links.begin(), links.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm;
  Eigen::AMDOrdering<int>()(graph, perm);
  // Eigen's orderings give the inverse permutation (the patch at each place).
  f_->order.assign(std::size_t(aggregates_), 0);
  for (int i = 0; i < aggregates_; ++i) f_->order[perm.indices()[i]] = i;
}

CoarseLevel::~CoarseLevel() = default;

Vec3 CoarseLevel::mode(int i, int k) const {
  Vec3 u;
  if (k < 3) {
    u = Vec3(Real(k == 0), Real(k == 1), Real(k == 2));
  } else {
    const Vec3 d = (at_[i] - centre_[agg_[i]]) * scale_;
    u = cross(Vec3(Real(k == 3), Real(k == 4), Real(k == 5)), d);
  }
  return free_part(u, held_[i]);
}

void CoarseLevel::factor(const std::vector<Tet>& tets, const Vec3* x, const Vec3* grad,
                         const Real* mu_vol, const Real* lambda_vol, const Real* beta,
                         const Real* mass, const Real* alpha, Real dt, const std::uint8_t* held) {
  const int nc = size();
  if (nc == 0) return;
  std::vector<int> count(std::size_t(aggregates_), 0);
  std::vector<Vec3d> sum(static_cast<std::size_t>(aggregates_));
  for (int i = 0; i < nodes_; ++i) {
    at_[i] = x[i];
    held_[i] = held ? held[i] : 0;
    if (agg_[i] < 0) continue;
    sum[agg_[i]] += Vec3d(x[i]);
    ++count[agg_[i]];
  }
  for (int g = 0; g < aggregates_; ++g) centre_[g] = Vec3(sum[g] / double(count[g]));
  Factor& F = *f_;
  std::fill(F.block.begin(), F.block.end(), 0.0);
  for (int i = 0; i < nodes_; ++i) {
    const int g = agg_[i];
    if (g < 0) continue;
    const double m = double(mass[i]) * (1.0 + double(dt) * double(alpha[i]));
    Vec3 u[6];
    for (int k = 0; k < 6; ++k) u[k] = mode(i, k);
    double* a = F.at(g, g);
    for (int k = 0; k < 6; ++k)
      for (int l = 0; l < 6; ++l) a[6 * l + k] += m * double(dot(u[l], u[k]));
  }
  // The element part by patch rows, in parallel: patch h's blocks take the products of the
  // elements it has nodes in, in element order, so each entry sums as one serial pass over the
  // elements would (the same bits on any thread count). An element of several patches is
  // taken once by each.
  const int na_all = aggregates_;
#pragma omp parallel for schedule(dynamic, 4)
  for (int h = 0; h < na_all; ++h)
    for (int e = tet_start_[h]; e < tet_start_[h + 1]; ++e) {
      const int t = tet_of_[e];
      const Tet& tet = tets[t];
      int ag[4], na = 0, cg[4];
      for (int c = 0; c < 4; ++c) {
        const int g = cg[c] = agg_[tet.v[c]];
        if (g >= 0 && std::find(ag, ag + na, g) == ag + na) ag[na++] = g;
      }
      Vec3 u[4][6];
      for (int c = 0; c < 4; ++c)
        for (int k = 0; k < 6; ++k) u[c][k] = cg[c] >= 0 ? mode(tet.v[c], k) : Vec3();
      const Vec3 Pt[3] = {grad[3 * t], grad[3 * t + 1], grad[3 * t + 2]};
      const Real s = dt * (dt + beta[t]);
      for (int gi = 0; gi < na; ++gi) {
        double* a = F.at(h, ag[gi]);
        for (int k = 0; k < 6; ++k) {
          Vec3 w[4], out[4];
          for (int c = 0; c < 4; ++c) w[c] = cg[c] == ag[gi] ? u[c][k] : Vec3();
          stress_products(w, Pt, s * mu_vol[t], s * lambda_vol[t], Real(0), out);
          for (int c = 0; c < 4; ++c) {
            if (cg[c] != h) continue;
            for (int l = 0; l < 6; ++l) a[6 * l + k] += double(dot(u[c][l], out[c]));
          }
        }
      }
    }
  // The lower triangle in the factor's order, symmetric in exact arithmetic: the round-off
  // averaged away, column by column (patch h's six, then the patches it meets placed after it).
  const std::vector<int>& o = F.order;
  std::vector<int> by_place(static_cast<std::size_t>(aggregates_));
  for (int g = 0; g < aggregates_; ++g) by_place[o[g]] = g;
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(F.block.size() / 2 + std::size_t(18) * aggregates_);
  for (int H = 0; H < aggregates_; ++H) {
    const int h = by_place[H];
    for (int e = F.start[h]; e < F.start[h + 1]; ++e) {
      const int g = F.col[e];
      if (o[g] < H) continue;
      const double* gh = F.at(g, h);
      const double* hg = F.at(h, g);
      for (int k = 0; k < 6; ++k)
        for (int l = g == h ? k : 0; l < 6; ++l)
          entries.emplace_back(6 * o[g] + l, 6 * H + k, 0.5 * (gh[6 * l + k] + hg[6 * k + l]));
    }
  }
  Eigen::SparseMatrix<double> a(nc, nc);
  a.setFromTriplets(entries.begin(), entries.end());
  // The order is the patches' already: analysed afresh each time (cheap next to the factor),
  // so only the blocks are kept between factors.
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>> llt(
      a);
  if (llt.info() != Eigen::Success) {
    // A mode no node moves (an aggregate of collinear nodes): a tiny shift keeps it definite.
    double top = 0;
    for (int j = 0; j < nc; ++j) top = std::max(top, a.coeff(j, j));
    for (int j = 0; j < nc; ++j) a.coeffRef(j, j) += 1e-9 * top;
    llt.compute(a);
  }
  F.ok = llt.info() == Eigen::Success;
  if (F.ok) F.blocks_of_l(llt.matrixL().nestedExpression());
}

double CoarseLevel::add(const Vec3* r, Vec3* z, Vec3* p, const std::uint8_t* mask) {
  const int nc = size();
  if (nc == 0 || !f_->ok) return 0.0;
  // The modes are translations and e_k x d (d the node's scaled offset from its patch's
  // centroid), with the held components taken out, a diagonal projection H: mode_k . r =
  // e_k . (H r) for the translations and e_k . (d x H r) for the rotations, and the patch's
  // motion at the node is H (c_t + c_r x d).
  std::fill(y_.begin(), y_.end(), 0.0);
  for (int i = 0; i < nodes_; ++i) {
    const int g = agg_[i];
    if (g < 0) continue;
    const Vec3d hr(free_part(r[i], held_[i]));
    const Vec3d rot = cross(Vec3d((at_[i] - centre_[g]) * scale_), hr);
    double* y = y_.data() + 6 * g;
    y[0] += hr.x, y[1] += hr.y, y[2] += hr.z;
    y[3] += rot.x, y[4] += rot.y, y[5] += rot.z;
  }
  f_->solve(y_.data(), c_.data());
  double rw = 0;
  for (int i = 0; i < nodes_; ++i) {
    const int g = agg_[i];
    if (g < 0) continue;
    const double* ci = c_.data() + 6 * g;
    const Vec3d d((at_[i] - centre_[g]) * scale_);
    Vec3 w(Vec3d(ci[0], ci[1], ci[2]) + cross(Vec3d(ci[3], ci[4], ci[5]), d));
    w = free_part(w, held_[i]);
    if (mask) w = free_part(w, mask[i]);
    z[i] += w;
    if (p) p[i] += w;
    rw += double(dot(r[i], w));
  }
  return rw;
}

}  // namespace fem
}  // namespace sphfem
