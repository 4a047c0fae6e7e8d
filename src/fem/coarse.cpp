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
// fill-reducing order: the dense factor of the bench's bunny (915 unknowns) read 6.7 MB twice
// per CG iteration and took 0.3 G flops to refactor (docs/design.md, "Coarse level").
struct CoarseLevel::Factor {
  std::vector<int> start, col;  // blocks of patch g: its neighbours col[start[g]..start[g+1])
  std::vector<double> block;    // 36 per block, row-major: a(6 g + l, 6 h + k) at 6 l + k
  Eigen::SparseMatrix<double> a;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
  bool analysed = false;
  bool ok = false;

  double* at(int g, int h) {
    const auto first = col.begin() + start[g], last = col.begin() + start[g + 1];
    return block.data() + 36 * (std::lower_bound(first, last, h) - col.begin());
  }
};

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
  for (std::size_t t = 0; t < tets.size(); ++t) {
    const Tet& tet = tets[t];
    int ag[4], na = 0;
    for (int v : tet.v) {
      const int g = agg_[v];
      if (g >= 0 && std::find(ag, ag + na, g) == ag + na) ag[na++] = g;
    }
    if (na == 0) continue;
    const Vec3 Pt[3] = {grad[3 * t], grad[3 * t + 1], grad[3 * t + 2]};
    const Real s = dt * (dt + beta[t]);
    for (int gi = 0; gi < na; ++gi)
      for (int k = 0; k < 6; ++k) {
        Vec3 w[4], out[4];
        for (int c = 0; c < 4; ++c) w[c] = agg_[tet.v[c]] == ag[gi] ? mode(tet.v[c], k) : Vec3();
        stress_products(w, Pt, s * mu_vol[t], s * lambda_vol[t], Real(0), out);
        for (int c = 0; c < 4; ++c) {
          const int h = agg_[tet.v[c]];
          if (h < 0) continue;
          double* a = F.at(h, ag[gi]);
          for (int l = 0; l < 6; ++l) a[6 * l + k] += double(dot(mode(tet.v[c], l), out[c]));
        }
      }
  }
  // The lower triangle, symmetric in exact arithmetic: the round-off averaged away, column by
  // column (patch h's six, then the patches g >= h it meets, in order).
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(F.block.size() / 2 + std::size_t(18) * aggregates_);
  for (int h = 0; h < aggregates_; ++h)
    for (int e = F.start[h]; e < F.start[h + 1]; ++e) {
      const int g = F.col[e];
      if (g < h) continue;
      const double* gh = F.at(g, h);
      const double* hg = F.at(h, g);
      for (int k = 0; k < 6; ++k)
        for (int l = g == h ? k : 0; l < 6; ++l)
          entries.emplace_back(6 * g + l, 6 * h + k, 0.5 * (gh[6 * l + k] + hg[6 * k + l]));
    }
  F.a.resize(nc, nc);
  F.a.setFromTriplets(entries.begin(), entries.end());
  if (!F.analysed) {
    F.llt.analyzePattern(F.a);
    F.analysed = true;
  }
  F.llt.factorize(F.a);
  if (F.llt.info() != Eigen::Success) {
    // A mode no node moves (an aggregate of collinear nodes): a tiny shift keeps it definite.
    double top = 0;
    for (int j = 0; j < nc; ++j) top = std::max(top, F.a.coeff(j, j));
    for (int j = 0; j < nc; ++j) F.a.coeffRef(j, j) += 1e-9 * top;
    F.llt.factorize(F.a);
  }
  F.ok = F.llt.info() == Eigen::Success;
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
  Eigen::Map<Eigen::VectorXd> y(y_.data(), nc), c(c_.data(), nc);
  c = f_->llt.solve(y);
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
