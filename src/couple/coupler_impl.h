// Coupler over one execution backend: owns the pair, run and travel buffers and runs the
// stages of src/couple/stages.h. Included once per backend.
#pragma once

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "couple/contact_solve.h"
#include "couple/stages.h"
#include "fem/stages.h"
#include "sphfem/core/memory.h"
#include "sphfem/couple/coupler.h"

namespace sphfem {

template <class Exec>
class CouplerT final : public Coupler {
  static_assert(kMaxSurfaces == couple::kMaxSets, "one limit for the public and kernel views");

 public:
  CouplerT() {
    const MemSpace s = Exec::kSpace;
    flag_ = Buffer<std::uint32_t>(s);
    keys_ = Buffer<std::uint32_t>(s);
    vals_ = Buffer<std::uint32_t>(s);
    first_ = Buffer<std::uint32_t>(s);
    contacts_ = Buffer<couple::Contact>(s);
    slot_ = Buffer<std::uint32_t>(s);
    for (Buffer<Real>* b : {&mass_, &diag_, &blocks_, &scratch6_}) *b = Buffer<Real>(s);
    for (Buffer<Vec3>* b : {&x_, &r_, &z_, &p_, &q_, &xf_, &rf_, &zf_, &pf_, &qf_})
      *b = Buffer<Vec3>(s);
    pinvf_ = Buffer<fem::Sym3>(s);
    travel_ = Buffer<Real>(s);
    surface_v_ = Buffer<Vec3>(s);
    body_first_ = Buffer<int>(s);
    coeffs_ = Buffer<ContactCoeffs>(s);
  }

  DriftLimits travel(const HitArrays& hits, const FluidArrays& fluid,
                     const std::vector<CoupleSurface>& surfaces, Real skin, double dt) override {
    const couple::SurfacesView S = view(surfaces);
    check(hits, fluid);
    if (!(skin >= Real(0))) throw std::invalid_argument("Coupler::travel: skin must be >= 0");
    grow(travel_, fluid.n);
    grow(surface_v_, fluid.n);
    couple::travel(ex_, S, hit_view(hits), particles(fluid), skin, Real(dt), travel_.data(),
                   surface_v_.data());
    exec_sync(ex_);
    DriftLimits d;
    d.travel = travel_.data();
    d.surface_v = surface_v_.data();
    return d;
  }

  void push_out(const HitArrays& hits, const FluidArrays& fluid,
                const std::vector<CoupleSurface>& surfaces, Real skin) override {
    const couple::SurfacesView S = view(surfaces);
    check(hits, fluid);
    couple::push_out(ex_, S, hit_view(hits), fluid.n, fluid.x, fluid.v, skin);
    exec_sync(ex_);
  }

  CoupleStats apply(const HitArrays& hits, const FluidArrays& fluid,
                    const std::vector<CoupleSurface>& surfaces, NodeOperator* bodies) override {
    const couple::SurfacesView S = view(surfaces);
    check(hits, fluid);
    CoupleStats stats;
    stats.body_impulse.assign(std::size_t(S.bodies), Vec3d());
    const int n = fluid.n;
    if (n == 0) return stats;
    const couple::HitView h = hit_view(hits);
    const couple::ParticleView p = particles(fluid);

    // One contact per particle with a hit, in particle order.
    grow(flag_, n);
    const int bad = couple::flag_hits(ex_, h, n, S.faces, flag_.data());
    if (bad > 0)
      throw std::invalid_argument("Coupler::apply: " + std::to_string(bad) +
                                  " hits name a face beyond the " + std::to_string(S.faces) +
                                  " triangles of the surfaces given; pass the same surfaces, in "
                                  "the same order, as the ray caster");
    const int m = int(exclusive_scan(ex_, flag_.data(), flag_.data(), n));
    stats.contacts = m;
    if (m == 0) return stats;
    grow(contacts_, m);
    couple::Contact* c = contacts_.data();
    couple::contact_setup(ex_, S, h, p, flag_.data(), c);

    // The node list: (node, 3 c + corner) sorted by node, one run per node.
    const int e = 3 * m;
    for (Buffer<std::uint32_t>* b : {&keys_, &vals_, &flag_, &slot_}) grow(*b, e);
    couple::node_entries(ex_, c, m, S.nodes, keys_.data(), vals_.data());
    sort_pairs(ex_, keys_.data(), vals_.data(), e, key_bits(S.nodes + 1));
    const std::uint32_t* keys = keys_.data();
    const std::uint32_t none = std::uint32_t(S.nodes);  // entries of immovable nodes sort last
    const int entries =
        int(reduce_sum(ex_, e,
                       [=] SPHFEM_LAMBDA(int i) -> double { return keys[i] < none ? 1.0 : 0.0; }) +
            0.5);
    int runs = 0;
    if (entries > 0) {
      couple::run_heads(ex_, keys_.data(), entries, flag_.data());
      runs = int(exclusive_scan(ex_, flag_.data(), flag_.data(), entries));
      grow(first_, runs + 1);
      couple::run_starts(ex_, keys_.data(), vals_.data(), flag_.data(), entries, runs,
                         first_.data(), slot_.data());
      for (Buffer<Real>* b : {&mass_, &diag_}) grow(*b, runs);
      for (Buffer<Vec3>* b : {&x_, &r_, &z_, &p_, &q_}) grow(*b, runs);
    }

    // Active set: the approaching contacts first; then those that would pull leave it and
    // those pushed into approach join it, until it stays the same. From half the rounds on,
    // contacts only leave: a set that only shrinks cannot cycle to the cap.
    const Real mp = fluid.mass, inv_mp = Real(1) / fluid.mass;
    const Real fastest =
        reduce_max(ex_, m, Real(0), [=] SPHFEM_LAMBDA(int k) -> Real { return norm(c[k].u0); });
    const Real tol = std::max(Real(kTolerance) * fastest, Real(1e-9));
    // With the bodies' operator the node vectors span every node (read by node, no slot).
    const bool full = bodies && bodies->nodes() > 0 && runs > 0;
    if (full) prepare_full(*bodies, S.nodes);
    Vec3* dV = full ? xf_.data() : x_.data();
    const std::uint32_t* at = full ? nullptr : slot_.data();
    for (int round = 0; round < kMaxRounds; ++round) {
      couple::contact_rhs(ex_, c, m, mp);
      if (runs > 0) {
        couple::node_diagonal(ex_, c, vals_.data(), first_.data(), runs, mp, mass_.data(),
                              diag_.data());
        stats.iterations +=
            full ? solve_full(*bodies, c, m, runs, S.nodes, mp) : solve_nodes(c, m, runs, mp);
      }
      couple::contact_apply(ex_, c, m, at, dV, mp);
      ++stats.rounds;
      if (couple::contact_update(ex_, c, m, at, dV, tol, round < kMaxRounds / 2) == 0) break;
    }
    stats.residual =
        double(couple::contact_residual(ex_, c, m, at, runs > 0 ? dV : nullptr, inv_mp));
    couple::apply_to_particles(ex_, c, m, fluid.v, inv_mp);
    if (runs > 0) {
      couple::node_gather(ex_, c, vals_.data(), first_.data(), runs, couple::kImpulse, nullptr,
                          nullptr, r_.data());
      couple::apply_to_nodes(ex_, S, keys_.data(), first_.data(), runs, r_.data(),
                             full ? bodies->nodes() : 0);
      if (full) bodies->add_velocity(dV);
    }
    exec_sync(ex_);

    host_contacts_.resize(std::size_t(m));
    contacts_.download(host_contacts_.data(), std::size_t(m));
    std::vector<char> seen(std::size_t(S.faces), 0);
    for (const couple::Contact& k : host_contacts_) {
      if (!seen[std::size_t(k.face)]) ++stats.faces;
      seen[std::size_t(k.face)] = 1;
      const bool some = k.J.x != Real(0) || k.J.y != Real(0) || k.J.z != Real(0);
      stats.exchanges += some ? 1 : 0;
      stats.body_impulse[std::size_t(k.body)] += Vec3d(k.J);
    }
    return stats;
  }

  // Preconditioned CG on (M + m_p W P W^T) dV = m_p W P (u* - u0) over the node runs, from
  // dV = 0, to kCgTolerance of the right-hand side in the preconditioner's norm. Returns its
  // iterations; the solution is in x_. (Public: nvcc allows no device lambda in private
  // member functions.)
  int solve_nodes(couple::Contact* c, int m, int runs, Real mp) {
    const std::uint32_t *vals = vals_.data(), *first = first_.data(), *slot = slot_.data();
    Vec3 *x = x_.data(), *r = r_.data(), *z = z_.data(), *p = p_.data(), *q = q_.data();
    const Real *mass = mass_.data(), *diag = diag_.data();
    couple::node_gather(ex_, c, vals, first, runs, couple::kRhs, mass, nullptr, r);
    parallel_for(ex_, runs, [=] SPHFEM_LAMBDA(int k) {
      x[k] = Vec3();
      z[k] = r[k] / diag[k];
      p[k] = z[k];
    });
    double rz = reduce_sum(ex_, runs,
                           [=] SPHFEM_LAMBDA(int k) -> double { return double(dot(r[k], z[k])); });
    const double target = kCgTolerance * kCgTolerance * rz;
    int it = 0;
    while (rz > target && rz > 0 && it < kMaxCg) {
      couple::contact_apply(ex_, c, m, slot, p, mp);
      couple::node_gather(ex_, c, vals, first, runs, couple::kMatrix, mass, p, q);
      const double pq = reduce_sum(
          ex_, runs, [=] SPHFEM_LAMBDA(int k) -> double { return double(dot(p[k], q[k])); });
      if (!(pq > 0)) break;
      const Real alpha = Real(rz / pq);
      const double rz_new = reduce_sum(ex_, runs, [=] SPHFEM_LAMBDA(int k) -> double {
        x[k] += p[k] * alpha;
        r[k] -= q[k] * alpha;
        z[k] = r[k] / diag[k];
        return double(dot(r[k], z[k]));
      });
      const Real beta = Real(rz_new / rz);
      parallel_for(ex_, runs, [=] SPHFEM_LAMBDA(int k) { p[k] = z[k] + p[k] * beta; });
      rz = rz_new;
      ++it;
    }
    return it;
  }

  // The bodies' diagonal blocks of A (fixed over the rounds) and the node vectors over all
  // N nodes of the sets.
  void prepare_full(NodeOperator& A, int N) {
    if (A.nodes() > N)
      throw std::invalid_argument("Coupler::apply: the bodies' operator spans " +
                                  std::to_string(A.nodes()) + " nodes, the surface sets " +
                                  std::to_string(N) + "; the bodies must be the first set");
    grow(blocks_, 6 * A.nodes());
    grow(pinvf_, N);
    for (Buffer<Vec3>* b : {&xf_, &rf_, &zf_, &pf_, &qf_}) grow(*b, N);
    A.diagonal(blocks_.data());
  }

  // Preconditioned CG on (A + m_p W P W^T) dV = m_p W P (u* - u0) over every node: A the
  // bodies' step operator on its nodes, the lumped mass on any other node a contact moves
  // (nodes of the sets beyond the bodies'). Block-Jacobi preconditioner: A's diagonal blocks
  // plus the contacts' m_p sum w^2. Returns its iterations; the solution is in xf_.
  int solve_full(NodeOperator& A, couple::Contact* c, int m, int runs, int N, Real mp) {
    const int na = A.nodes();
    const std::uint32_t *vals = vals_.data(), *first = first_.data(), *keys = keys_.data();
    Vec3 *x = xf_.data(), *r = rf_.data(), *z = zf_.data(), *p = pf_.data(), *q = qf_.data();
    Vec3* run = r_.data();  // per-run sums
    const Real *mass = mass_.data(), *diag = diag_.data();
    const Real* blocks = blocks_.data();
    fem::Sym3* pinv = pinvf_.data();
    // The preconditioner's blocks: A's (bodies' nodes), then each run's contacts and, beyond
    // the bodies, its lumped mass; a node with neither is masked out.
    Real* b6 = scratch6(N);
    parallel_for(ex_, N, [=] SPHFEM_LAMBDA(int i) {
      for (int k = 0; k < 6; ++k) b6[6 * i + k] = i < na ? blocks[6 * i + k] : Real(0);
      x[i] = Vec3();
      r[i] = Vec3();
    });
    couple::node_gather(ex_, c, vals, first, runs, couple::kRhs, mass, nullptr, run);
    parallel_for(ex_, runs, [=] SPHFEM_LAMBDA(int k) {
      const int i = int(keys[first[k]]);
      const Real d = diag[k] - mass[k] + (i < na ? Real(0) : mass[k]);
      for (int a = 0; a < 3; ++a) b6[6 * i + a] += d;
      r[i] = run[k];
    });
    double rz = reduce_sum(ex_, N, [=] SPHFEM_LAMBDA(int i) -> double {
      const Real* b = b6 + 6 * i;
      pinv[i] = b[0] > Real(0) ? fem::inverse_block(b) : fem::Sym3{0, 0, 0, 0, 0, 0};
      z[i] = pinv[i] * r[i];
      p[i] = z[i];
      return double(dot(r[i], z[i]));
    });
    const double target = kCgTolerance * kCgTolerance * rz;
    int it = 0;
    while (rz > target && rz > 0 && it < kMaxCg) {
      A.apply(p, q);
      if (N > na) parallel_for(ex_, N - na, [=] SPHFEM_LAMBDA(int k) { q[na + k] = Vec3(); });
      couple::contact_apply(ex_, c, m, nullptr, p, mp);
      couple::node_gather(ex_, c, vals, first, runs, couple::kContact, nullptr, nullptr, run);
      parallel_for(ex_, runs, [=] SPHFEM_LAMBDA(int k) {
        const int i = int(keys[first[k]]);
        q[i] += run[k];
        if (i >= na) q[i] += p[i] * mass[k];
      });
      const double pq = reduce_sum(
          ex_, N, [=] SPHFEM_LAMBDA(int i) -> double { return double(dot(p[i], q[i])); });
      if (!(pq > 0)) break;
      const Real alpha = Real(rz / pq);
      const double rz_new = reduce_sum(ex_, N, [=] SPHFEM_LAMBDA(int i) -> double {
        x[i] += p[i] * alpha;
        r[i] -= q[i] * alpha;
        z[i] = pinv[i] * r[i];
        return double(dot(r[i], z[i]));
      });
      const Real beta = Real(rz_new / rz);
      parallel_for(ex_, N, [=] SPHFEM_LAMBDA(int i) { p[i] = z[i] + p[i] * beta; });
      rz = rz_new;
      ++it;
    }
    return it;
  }

 private:
  Real* scratch6(int N) {
    grow(scratch6_, 6 * N);
    return scratch6_.data();
  }

  template <class T>
  static void grow(Buffer<T>& b, int n) {
    if (b.size() < std::size_t(n)) b.resize(std::size_t(n) + std::size_t(n) / 4);
  }

  static int key_bits(int keys) {
    int bits = 1;
    while ((1ll << bits) < keys) ++bits;
    return bits;
  }

  static couple::HitView hit_view(const HitArrays& a) {
    couple::HitView h;
    h.face = a.face;
    h.t = a.t;
    h.u = a.u;
    h.v = a.v;
    h.bias = a.bias;
    return h;
  }

  static couple::ParticleView particles(const FluidArrays& f) {
    couple::ParticleView p;
    p.n = f.n;
    p.x = f.x;
    p.v = f.v;
    p.mass = f.mass;
    return p;
  }

  void check(const HitArrays& hits, const FluidArrays& fluid) const {
    if (fluid.space != Exec::kSpace || hits.space != Exec::kSpace)
      throw std::invalid_argument(
          "Coupler: fluid and hit arrays must live in the coupler's memory space (make the "
          "coupler with the fluid solver's backend)");
    if (fluid.n > 0 && !(hits.face && hits.t && hits.u && hits.v && fluid.x && fluid.v))
      throw std::invalid_argument("Coupler: a hit or particle array is missing");
    if (fluid.n > 0 && !(fluid.mass > Real(0)))
      throw std::invalid_argument("Coupler: the particle mass must be positive");
  }

  // The kernels' view of the sets; the bodies' face ranges and coefficients are uploaded when
  // they differ from the last call's.
  couple::SurfacesView view(const std::vector<CoupleSurface>& sets) {
    if (sets.size() > std::size_t(kMaxSurfaces))
      throw std::invalid_argument("Coupler: at most " + std::to_string(kMaxSurfaces) +
                                  " surface sets per call, got " + std::to_string(sets.size()));
    couple::SurfacesView S;
    std::vector<int> body_first;
    std::vector<ContactCoeffs> coeffs;
    int face = 0, nodes = 0;
    for (std::size_t k = 0; k < sets.size(); ++k) {
      const CoupleSurface& c = sets[k];
      const std::string where = "Coupler: surface set " + std::to_string(k) + ": ";
      if (c.space != Exec::kSpace)
        throw std::invalid_argument(where +
                                    "arrays live in another memory space than the "
                                    "coupler's backend");
      if (c.triangles < 0 || c.nodes < 0 || (c.triangles > 0 && !(c.tri && c.x)))
        throw std::invalid_argument(where + "triangles or node positions missing");
      std::vector<int> off = c.tri_offset;
      if (off.empty()) off = {0, c.triangles};
      if (off.front() != 0 || off.back() != c.triangles || !std::is_sorted(off.begin(), off.end()))
        throw std::invalid_argument(where + "tri_offset must rise from 0 to the " +
                                    std::to_string(c.triangles) + " triangles");
      if (c.coeffs.size() + 1 != off.size())
        throw std::invalid_argument(where + std::to_string(off.size() - 1) + " bodies but " +
                                    std::to_string(c.coeffs.size()) +
                                    " contact coefficients; give one per body");
      for (const ContactCoeffs& cc : c.coeffs)
        if (!(cc.restitution >= 0 && cc.restitution <= 1 && cc.slip >= 0 && cc.slip <= 1))
          throw std::invalid_argument(where + "restitution and slip must lie in [0, 1]");
      for (std::size_t b = 0; b + 1 < off.size(); ++b) body_first.push_back(face + off[b]);
      coeffs.insert(coeffs.end(), c.coeffs.begin(), c.coeffs.end());
      couple::SurfaceView& s = S.set[k];
      s.first = face;
      s.node_base = nodes;
      s.triangles = c.triangles;
      s.tri = c.tri;
      s.x = c.x;
      s.v = c.v;
      s.mass = c.mass;
      s.pinned = c.pinned;
      s.impulse = c.impulse;
      face += c.triangles;
      nodes += c.nodes;
    }
    body_first.push_back(face);
    S.count = int(sets.size());
    S.faces = face;
    S.nodes = nodes;
    S.bodies = int(coeffs.size());
    if (body_first != host_body_first_ || !same(coeffs, host_coeffs_)) {
      host_body_first_ = body_first;
      host_coeffs_ = coeffs;
      body_first_.resize(body_first.size());
      body_first_.upload(body_first.data(), body_first.size());
      coeffs_.resize(std::max<std::size_t>(coeffs.size(), 1));
      if (!coeffs.empty()) coeffs_.upload(coeffs.data(), coeffs.size());
    }
    S.body_first = body_first_.data();
    S.coeffs = coeffs_.data();
    return S;
  }

  static bool same(const std::vector<ContactCoeffs>& a, const std::vector<ContactCoeffs>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (a[i].restitution != b[i].restitution || a[i].slip != b[i].slip) return false;
    return true;
  }

  // The joint solve: contacts meet their laws to this fraction of the fastest approach; the
  // sweeps stop at kMaxSweeps whatever the residual (reported in CoupleStats).
  static constexpr double kTolerance = 1e-5;    // of the fastest approach: "pushed in"
  static constexpr double kCgTolerance = 1e-6;  // relative, in the preconditioner's norm
  static constexpr int kMaxCg = 500;
  static constexpr int kMaxRounds = 16;  // active-set changes

  Exec ex_;
  Buffer<std::uint32_t> flag_, keys_, vals_, first_, slot_;
  Buffer<couple::Contact> contacts_;
  Buffer<Real> mass_, diag_;
  Buffer<Vec3> x_, r_, z_, p_, q_;
  Buffer<Real> blocks_, scratch6_;  // with the bodies' operator: A's blocks, the preconditioner's
  Buffer<fem::Sym3> pinvf_;
  Buffer<Vec3> xf_, rf_, zf_, pf_, qf_;  // node vectors over every node
  Buffer<Real> travel_;
  Buffer<Vec3> surface_v_;
  Buffer<int> body_first_;
  Buffer<ContactCoeffs> coeffs_;
  std::vector<int> host_body_first_;
  std::vector<ContactCoeffs> host_coeffs_;
  std::vector<couple::Contact> host_contacts_;
};

}  // namespace sphfem
