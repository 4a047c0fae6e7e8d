// Coupler over one execution backend: owns the pair, run and travel buffers and runs the
// stages of src/couple/stages.h. Included once per backend.
#pragma once

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/node_sums.h"
#include "couple/stages.h"
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
    runs_ = Buffer<couple::RunResult>(s);
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
                    const std::vector<CoupleSurface>& surfaces) override {
    const couple::SurfacesView S = view(surfaces);
    check(hits, fluid);
    CoupleStats stats;
    stats.body_impulse.assign(std::size_t(S.bodies), Vec3d());
    const int n = fluid.n;
    if (n == 0) return stats;
    const couple::HitView h = hit_view(hits);
    const couple::ParticleView p = particles(fluid);

    // Compact the hits into pairs, in particle order (so the sums below are deterministic).
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
    grow(keys_, m);
    grow(vals_, m);
    couple::make_pairs(ex_, S, h, p, flag_.data(), keys_.data(), vals_.data());

    // Group by (face, side): radix sort, run heads, their scan and the run starts.
    sort_pairs(ex_, keys_.data(), vals_.data(), m, key_bits(2 * S.faces));
    couple::run_heads(ex_, keys_.data(), m, flag_.data());
    const int runs = int(exclusive_scan(ex_, flag_.data(), flag_.data(), m));
    grow(first_, runs + 1);
    couple::run_starts(ex_, keys_.data(), flag_.data(), m, runs, first_.data());

    grow(runs_, runs);
    couple::exchange(ex_, S, h, p, keys_.data(), vals_.data(), first_.data(), runs, runs_.data());
    // +J into each set's nodes, node by node in run order.
    const couple::RunResult* res = runs_.data();
    for (int set = 0; set < S.count; ++set) {
      if (!S.set[set].impulse) continue;
      node_sums_.add(
          ex_, 3 * runs, surfaces[std::size_t(set)].nodes,
          [=] SPHFEM_LAMBDA(int k, int& node, Vec3& value) {
            const couple::RunResult& r = res[k / 3];
            if (r.set != set) return;
            node = r.node[k % 3];
            value = r.node_impulse[k % 3];
          },
          S.set[set].impulse);
    }
    exec_sync(ex_);

    host_runs_.resize(std::size_t(runs));
    runs_.download(host_runs_.data(), std::size_t(runs));
    for (const couple::RunResult& r : host_runs_) {
      stats.faces += r.new_face;
      stats.exchanges += r.exchanged;
      stats.body_impulse[std::size_t(r.body)] += Vec3d(r.impulse);
    }
    return stats;
  }

 private:
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
    int face = 0;
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
      s.triangles = c.triangles;
      s.tri = c.tri;
      s.x = c.x;
      s.v = c.v;
      s.mass = c.mass;
      s.pinned = c.pinned;
      s.impulse = c.impulse;
      face += c.triangles;
    }
    body_first.push_back(face);
    S.count = int(sets.size());
    S.faces = face;
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

  Exec ex_;
  NodeSums<Exec> node_sums_;
  Buffer<std::uint32_t> flag_, keys_, vals_, first_;
  Buffer<couple::RunResult> runs_;
  Buffer<Real> travel_;
  Buffer<Vec3> surface_v_;
  Buffer<int> body_first_;
  Buffer<ContactCoeffs> coeffs_;
  std::vector<int> host_body_first_;
  std::vector<ContactCoeffs> host_coeffs_;
  std::vector<couple::RunResult> host_runs_;
};

}  // namespace sphfem
