#include "fem/coarse.h"

// Serial: Eigen's OpenMP products block by the thread count, which would change the bits.
#define EIGEN_DONT_PARALLELIZE
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>

#include "fem/corotated.h"
#include "fem/stages.h"  // free_part

namespace sphfem {
namespace fem {

struct CoarseLevel::Factor {
  Eigen::MatrixXd a;
  Eigen::LLT<Eigen::MatrixXd> llt;
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
  Eigen::MatrixXd& a = f_->a;
  a.setZero(nc, nc);
  for (int i = 0; i < nodes_; ++i) {
    const int g = agg_[i];
    if (g < 0) continue;
    const double m = double(mass[i]) * (1.0 + double(dt) * double(alpha[i]));
    Vec3 u[6];
    for (int k = 0; k < 6; ++k) u[k] = mode(i, k);
    for (int k = 0; k < 6; ++k)
      for (int l = 0; l < 6; ++l) a(6 * g + l, 6 * g + k) += m * double(dot(u[l], u[k]));
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
          for (int l = 0; l < 6; ++l)
            a(6 * h + l, 6 * ag[gi] + k) += double(dot(mode(tet.v[c], l), out[c]));
        }
      }
  }
  // Symmetric in exact arithmetic; average the round-off away before factoring.
  a = 0.5 * (a + a.transpose()).eval();
  f_->llt.compute(a);
  if (f_->llt.info() != Eigen::Success) {
    // A mode no node moves (an aggregate of collinear nodes): a tiny shift keeps it definite.
    const double shift = 1e-9 * a.diagonal().maxCoeff();
    a.diagonal().array() += shift;
    f_->llt.compute(a);
  }
}

double CoarseLevel::add(const Vec3* r, Vec3* z, Vec3* p, const std::uint8_t* mask) {
  const int nc = size();
  if (nc == 0 || f_->llt.info() != Eigen::Success) return 0.0;
  std::fill(y_.begin(), y_.end(), 0.0);
  for (int i = 0; i < nodes_; ++i) {
    const int g = agg_[i];
    if (g < 0) continue;
    for (int k = 0; k < 6; ++k) y_[6 * g + k] += double(dot(mode(i, k), r[i]));
  }
  Eigen::Map<Eigen::VectorXd> y(y_.data(), nc), c(c_.data(), nc);
  c = f_->llt.solve(y);
  double rw = 0;
  for (int i = 0; i < nodes_; ++i) {
    const int g = agg_[i];
    if (g < 0) continue;
    Vec3 w;
    for (int k = 0; k < 6; ++k) w += mode(i, k) * Real(c_[6 * g + k]);
    if (mask) w = free_part(w, mask[i]);
    z[i] += w;
    if (p) p[i] += w;
    rw += double(dot(r[i], w));
  }
  return rw;
}

}  // namespace fem
}  // namespace sphfem
