// FluidSolver over one execution backend: owns the state buffers and runs the stages of
// src/sph/stages.h in the order of one step. Included once per backend.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "sph/moving_stages.h"
#include "sph/stages.h"
#include "sphfem/core/memory.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

using stages::BoundaryView;
using stages::FluidView;
using stages::Walls;

template <class Exec>
class SolverT final : public FluidSolver {
 public:
  explicit SolverT(const FluidModel& m) : model_(m), P_(m.params) {
    const MemSpace s = Exec::kSpace;
    cap_ = std::max<int>(m.capacity, int(m.x0.size()));
    for (Buffer<Vec3>* b : {&x_, &v_, &a_, &tmp3_}) *b = Buffer<Vec3>(s, cap_);
    for (Buffer<Real>* b : {&rho_, &p_, &alpha_, &kappa_, &ksum_, &warm_div_, &warm_dens_, &tmpr_})
      *b = Buffer<Real>(s, cap_);
    warm_div_.zero();
    warm_dens_.zero();
    nb_ = Buffer<int>(s, cap_);
    full_ = Buffer<int>(s, cap_);
    // Room for twice a full support's neighbours; a particle compressed beyond that scans the
    // grid instead (stages::for_fluid_neighbors).
    nbr_cap_ = std::max(32, 2 * m.params.full_neighbors);
    nbr_ = Buffer<std::uint32_t>(s, std::size_t(cap_) * std::size_t(nbr_cap_));
    nbr_n_ = Buffer<int>(s, cap_);
    for (Buffer<std::uint32_t>* b : {&id_, &tmpu_, &keys_, &perm_})
      *b = Buffer<std::uint32_t>(s, cap_);
    start_ = Buffer<std::uint32_t>(s, std::size_t(m.grid.cells()) + 1);

    n_ = int(m.x0.size());
    x_.upload(m.x0.data(), n_);
    v_.upload(m.v0.data(), n_);
    std::vector<std::uint32_t> ids(n_);
    for (int i = 0; i < n_; ++i) ids[i] = std::uint32_t(i);
    id_.upload(ids.data(), n_);
    next_id_ = std::uint32_t(n_);

    upload_boundary();
    // The space beyond a surface filled like the tank's walls (sph/surface_density.h).
    const double layer = double(P_.spacing) / double(P_.h);
    const double lattice_mass =
        double(P_.mass) / (double(P_.rho0) * std::pow(double(P_.spacing), 3));
    const std::vector<Real> half =
        half_space_table(P_.kernel, kHalfSpaceSteps, layer, lattice_mass);
    half_ = Buffer<Real>(s, half.size());
    half_.upload(half.data(), half.size());
    moving_share_ = stages::moving_rest_share(half, half_space_table(P_.kernel, kHalfSpaceSteps),
                                              kHalfSpaceSteps, layer);
    for (const EmitterModel& e : m.emitters) {
      discs_.emplace_back(s, e.disc.size());
      discs_.back().upload(e.disc.data(), e.disc.size());
      travelled_.push_back(0.0);
    }
  }

  int count() const override { return n_; }
  double time() const override { return t_; }
  long steps() const override { return steps_; }
  const StepProfile& profile() const override { return prof_; }
  void reset_profile() override { prof_.clear(); }
  const FluidModel& model() const override { return model_; }
  void set_hook(StepHook* hook) override { hook_ = hook; }

  void set_moving_samples(const std::vector<SurfaceSample>& samples, const std::vector<Tri>& tris,
                          int nodes) override {
    const int n = int(samples.size());
    std::vector<int> tri(n);
    std::vector<Vec3> w(n);
    // Gather lists node -> (sample, weight), so the nodes sum their samples' impulses in a
    // fixed order without atomics.
    std::vector<int> start(std::size_t(std::max(nodes, 0)) + 1, 0);
    for (int k = 0; k < n; ++k) {
      const SurfaceSample& sm = samples[k];
      if (sm.tri < 0 || sm.tri >= int(tris.size()))
        throw std::invalid_argument("set_moving_samples: sample " + std::to_string(k) +
                                    " names triangle " + std::to_string(sm.tri) + " of " +
                                    std::to_string(tris.size()));
      tri[k] = sm.tri;
      w[k] = Vec3(sm.w[0], sm.w[1], sm.w[2]);
      for (int c = 0; c < 3; ++c) {
        const int node = tris[sm.tri].v[c];
        if (node < 0 || node >= nodes)
          throw std::invalid_argument("set_moving_samples: triangle " + std::to_string(sm.tri) +
                                      " names node " + std::to_string(node) + " of " +
                                      std::to_string(nodes));
        if (sm.w[c] != Real(0)) ++start[node + 1];
      }
    }
    for (int i = 0; i < nodes; ++i) start[i + 1] += start[i];
    std::vector<int> sample(start.back());
    std::vector<Real> weight(start.back());
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c) {
        if (samples[k].w[c] == Real(0)) continue;
        const int e = fill[tris[samples[k].tri].v[c]]++;
        sample[e] = k;
        weight[e] = samples[k].w[c];
      }
    const MemSpace s = Exec::kSpace;
    const std::size_t cap = std::size_t(std::max(n, 1));
    msamples_ = n;
    mnodes_ = n ? nodes : 0;
    mtri_ = Buffer<int>(s, cap);
    mtri_.upload(tri.data(), n);
    mw_ = Buffer<Vec3>(s, cap);
    mw_.upload(w.data(), n);
    for (Buffer<Vec3>* b : {&mx_, &mv_, &mtmpx_, &mtmpv_, &mimp_}) *b = Buffer<Vec3>(s, cap);
    for (Buffer<Real>* b :
         {&mpsi_, &mrest_, &mpw_, &mrho_, &malpha_, &mkappa_, &mksum_, &mwarm_div_, &mwarm_dens_}) {
      *b = Buffer<Real>(s, cap);
      b->zero();
    }
    mnb_rest_ = Buffer<int>(s, cap);
    mfull_ = Buffer<int>(s, cap);
    for (Buffer<std::uint32_t>* b : {&mkeys_, &mperm_, &mslot_}) *b = Buffer<std::uint32_t>(s, cap);
    mstart_ = Buffer<std::uint32_t>(s, std::size_t(model_.grid.cells()) + 1);
    mnode_start_ = Buffer<int>(s, start.size());
    mnode_start_.upload(start.data(), start.size());
    mnode_sample_ = Buffer<int>(s, std::max<std::size_t>(sample.size(), 1));
    mnode_sample_.upload(sample.data(), sample.size());
    mnode_w_ = Buffer<Real>(s, std::max<std::size_t>(weight.size(), 1));
    mnode_w_.upload(weight.data(), weight.size());
    mactive_ = 0;
  }

  // A fluid alone: the stages in Simulation::step's order, with the hook around the drift.
  StepInfo step(double dt_limit) override {
    StepInfo info;
    timed(Stage::Neighbors,
          [&] { sort(hook_ && msamples_ ? hook_->moving_boundary(arrays()) : MovingSurface()); });
    SurfaceProximity near;
    if (hook_) timed(Stage::Proximity, [&] { near = hook_->proximity(arrays()); });
    timed(Stage::Density, [&] { density(near); });
    const double dt = time_step(dt_limit, info);
    timed(Stage::Divergence, [&] { divergence(info); });
    timed(Stage::Forces, [&] { forces(info); });
    timed(Stage::Pressure, [&] { pressure(info); });
    DriftLimits limits;
    if (hook_) timed(Stage::Collide, [&] { limits = hook_->before_drift(arrays(), dt); });
    timed(Stage::Drift, [&] { drift(limits, info); });
    if (hook_) timed(Stage::Exchange, [&] { hook_->after_drift(arrays(), dt); });
    timed(Stage::Emit, [&] { emit(info); });
    ++prof_.steps;
    return info;
  }

  void sort(const MovingSurface& moving) override {
    place_moving_samples(moving);
    sort_particles();
    exec_sync(ex_);
  }

  void density(const SurfaceProximity& near) override {
    prox_ = near;
    const bool dfsph = model_.solver == SolverKind::DFSPH;
    const Walls w = walls();
    FluidView f = view();
    const GridView g = grid(start_.data());
    stages::density(ex_, P_, f, g, w, dfsph);
    if (dfsph) {
      active_walls_ = stages::wall_density(ex_, P_, f, g, w.fixed);
      if (w.moving.n) active_walls_ += stages::wall_density(ex_, P_, f, g, w.moving);
      stages::dfsph_smooth_warm(ex_, P_, f, g, w, tmpr_.data());
      warm_dens_.swap(tmpr_);
      p_.zero();
    }
    exec_sync(ex_);
  }

  double time_step(double dt_limit, StepInfo& info) override {
    double dt_free = 0;
    dt_ = choose_dt(dt_limit, dt_free);
    // How much of a full step this one is: the pace of density corrections and the weight of
    // this step in the warm starts (stages::dfsph_source, stages::dfsph_remember).
    pace_ = Real(dt_ / dt_free);
    info.dt = dt_;
    return dt_;
  }

  void divergence(StepInfo& info) override {
    if (model_.solver != SolverKind::DFSPH) return;
    const Walls w = walls();
    info.divergence_iterations =
        solve(view(), grid(start_.data()), w, Real(dt_), pace_, true, model_.divergence_tolerance);
    if (w.moving.n)
      stages::sample_pressure_impulse(ex_, P_, view(), grid(start_.data()), w.moving, Real(dt_),
                                      mimp_.data());
    exec_sync(ex_);
  }

  void forces(StepInfo&) override {
    const bool wcsph = model_.solver == SolverKind::WCSPH;
    const Walls w = walls();
    FluidView f = view();
    const GridView g = grid(start_.data());
    const Real rdt = Real(dt_);
    if (wcsph) {
      stages::wall_pressure(ex_, P_, f, g, w.fixed);
      if (w.moving.n) stages::wall_pressure(ex_, P_, f, g, w.moving);
    }
    stages::accelerations(ex_, P_, f, g, w, wcsph, rdt);
    if (w.moving.n) stages::sample_force_impulse(ex_, P_, f, g, w.moving, wcsph, rdt, mimp_.data());
    stages::kick(ex_, f, rdt);
    exec_sync(ex_);
  }

  void pressure(StepInfo& info) override {
    const Walls w = walls();
    if (model_.solver == SolverKind::DFSPH) {
      info.pressure_iterations =
          solve(view(), grid(start_.data()), w, Real(dt_), pace_, false, model_.density_tolerance);
      info.density_error = last_error_;
      if (w.moving.n)
        stages::sample_pressure_impulse(ex_, P_, view(), grid(start_.data()), w.moving, Real(dt_),
                                        mimp_.data());
    }
    if (w.moving.n && moving_.impulse)
      stages::node_impulse(ex_, mnodes_, mnode_start_.data(), mnode_sample_.data(), mnode_w_.data(),
                           mslot_.data(), mimp_.data(), moving_.impulse);
    exec_sync(ex_);
  }

  void drift(const DriftLimits& limits, StepInfo& info) override {
    info.clamped = stages::drift(ex_, P_, view(), Real(dt_), limits.travel, limits.surface_v);
    exec_sync(ex_);
    t_ += dt_;
    ++steps_;
    prox_ = SurfaceProximity();
  }

  void emit(StepInfo& info) override {
    info.emitted = emit_layers(dt_);
    exec_sync(ex_);
  }

  FluidArrays arrays() override {
    FluidArrays a;
    a.space = Exec::kSpace;
    a.n = n_;
    a.x = x_.data();
    a.v = v_.data();
    a.id = id_.data();
    a.mass = P_.mass;
    a.radius = P_.spacing / Real(2);
    return a;
  }

  // Densities and neighbour counts of the present positions, computed on a cell-sorted copy
  // (scratch buffers only) and returned in the state's order, which stays as it is.
  void snapshot(FluidSnapshot& out, SurfaceQuery* surfaces) override {
    if (!surfaces) surfaces = hook_;
    const bool dfsph = model_.solver == SolverKind::DFSPH;
    const int n = n_;
    const GridView g = grid(start_.data());
    // perm_[k]: the state index of the k-th particle in cell order.
    stages::cell_keys(ex_, g, x_.data(), keys_.data(), perm_.data(), n);
    sort_pairs(ex_, keys_.data(), perm_.data(), n, key_bits());
    stages::gather(ex_, x_.data(), tmp3_.data(), perm_.data(), n);
    stages::gather(ex_, v_.data(), a_.data(), perm_.data(), n);
    stages::cell_starts(ex_, keys_.data(), start_.data(), n, g.cells());
    FluidView f = view();
    f.x = tmp3_.data();
    f.v = a_.data();
    f.p = tmpr_.data();
    f.warm_div = f.warm_dens = nullptr;
    f.gwall = nullptr;
    FluidArrays sorted = arrays();
    sorted.x = tmp3_.data();
    sorted.v = a_.data();
    sorted.id = nullptr;
    place_moving_samples(surfaces && msamples_ ? surfaces->moving_boundary(sorted)
                                               : MovingSurface());
    prox_ = surfaces ? surfaces->proximity(sorted) : SurfaceProximity();
    stages::density(ex_, P_, f, g, walls(), /*with_alpha=*/false);
    prox_ = SurfaceProximity();
    exec_sync(ex_);
    std::vector<std::uint32_t> perm(n);
    std::vector<Real> rho(n), p(n);
    std::vector<int> nb(n);
    perm_.download(perm.data(), n);
    rho_.download(rho.data(), n);
    nb_.download(nb.data(), n);
    tmpr_.download(p.data(), n);
    out.n = n;
    out.x.resize(n);
    out.v.resize(n);
    out.rho.resize(n);
    out.p.resize(n);
    out.id.resize(n);
    out.neighbors.resize(n);
    x_.download(out.x.data(), n);
    v_.download(out.v.data(), n);
    id_.download(out.id.data(), n);
    // DFSPH: the pressure of the last solve, in the state's order; WCSPH: the equation of state
    // at the present densities.
    if (dfsph) p_.download(out.p.data(), n);
    for (int k = 0; k < n; ++k) {
      out.rho[perm[k]] = rho[k];
      out.neighbors[perm[k]] = nb[k];
      if (!dfsph) out.p[perm[k]] = p[k];
    }
  }

  void save(FluidState& s) const override {
    s.n = n_;
    s.time = t_;
    s.steps = steps_;
    s.next_id = next_id_;
    s.capacity_warned = capacity_warned_;
    s.emitter_travel = travelled_;
    s.x.resize(n_);
    s.v.resize(n_);
    s.id.resize(n_);
    s.warm_div.resize(n_);
    s.warm_dens.resize(n_);
    x_.download(s.x.data(), n_);
    v_.download(s.v.data(), n_);
    id_.download(s.id.data(), n_);
    warm_div_.download(s.warm_div.data(), n_);
    warm_dens_.download(s.warm_dens.data(), n_);
  }

  void load(const FluidState& s) override {
    const std::size_t n = std::size_t(s.n);
    if (s.n < 0 || s.n > cap_)
      throw std::invalid_argument("fluid state: " + std::to_string(s.n) +
                                  " particles, the model holds at most " + std::to_string(cap_));
    if (s.x.size() != n || s.v.size() != n || s.id.size() != n || s.warm_div.size() != n ||
        s.warm_dens.size() != n)
      throw std::invalid_argument("fluid state: arrays of another length than its " +
                                  std::to_string(s.n) + " particles");
    if (s.emitter_travel.size() != travelled_.size())
      throw std::invalid_argument("fluid state: " + std::to_string(s.emitter_travel.size()) +
                                  " emitters, the model has " + std::to_string(travelled_.size()));
    n_ = s.n;
    t_ = s.time;
    steps_ = s.steps;
    next_id_ = s.next_id;
    capacity_warned_ = s.capacity_warned;
    travelled_ = s.emitter_travel;
    x_.upload(s.x.data(), n);
    v_.upload(s.v.data(), n);
    id_.upload(s.id.data(), n);
    warm_div_.upload(s.warm_div.data(), n);
    warm_dens_.upload(s.warm_dens.data(), n);
    p_.zero();
    exec_sync(ex_);
  }

 private:
  template <class F>
  void timed(Stage ph, F&& fn) {
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    exec_sync(ex_);
    prof_.ms[int(ph)] +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }

  GridView grid(const std::uint32_t* start) const {
    GridView g;
    g.lo = model_.grid.lo;
    g.inv_cell = Real(1) / model_.grid.cell;
    g.nx = model_.grid.nx;
    g.ny = model_.grid.ny;
    g.nz = model_.grid.nz;
    g.start = start;
    return g;
  }

  BoundaryView boundary() {
    BoundaryView b;
    b.n = int(model_.boundary_x.size());
    b.x = bx_.data();
    b.psi = bpsi_.data();
    b.rest = brest_.data();
    b.nb_rest = bnb_rest_.data();
    b.pw = bpw_.data();
    b.rho = brho_.data();
    b.alpha = balpha_.data();
    b.full = bfull_.data();
    b.kappa = bkappa_.data();
    b.kappa_sum = bksum_.data();
    b.warm_div = bwarm_div_.data();
    b.warm_dens = bwarm_dens_.data();
    b.grid = grid(bstart_.data());
    if (model_.boundary_x.empty()) b.grid.nx = 0;
    return b;
  }

  // Moving samples of this step (n = 0 when none were placed).
  BoundaryView moving() {
    BoundaryView b;
    b.n = mactive_;
    if (!mactive_) {
      b.grid.nx = 0;
      return b;
    }
    b.x = mx_.data();
    b.v = moving_.v ? mv_.data() : nullptr;
    b.psi = mpsi_.data();
    b.rest = mrest_.data();
    b.nb_rest = mnb_rest_.data();
    b.pw = mpw_.data();
    b.rho = mrho_.data();
    b.alpha = malpha_.data();
    b.full = mfull_.data();
    b.kappa = mkappa_.data();
    b.kappa_sum = mksum_.data();
    b.warm_div = mwarm_div_.data();
    b.warm_dens = mwarm_dens_.data();
    b.grid = grid(mstart_.data());
    return b;
  }

  Walls walls() {
    Walls w;
    w.fixed = boundary();
    w.moving = moving();
    if (prox_.dist && prox_.normal) {
      w.surface.dist = prox_.dist;
      w.surface.normal = prox_.normal;
      w.surface.vel = prox_.velocity;
      w.surface.dv = prox_.dv;
    }
    w.surface.half.table = half_.data();
    w.surface.half.n = kHalfSpaceSteps;
    w.surface.half.inv_h = Real(1) / P_.h;
    return w;
  }

  // Boundary-particle coupling: the samples on the given surface as it is now, sorted into
  // their own cell grid, with psi and (DFSPH) their walls-alone density; impulses start at 0.
  void place_moving_samples(const MovingSurface& surface) {
    mactive_ = 0;
    moving_ = MovingSurface();
    if (!msamples_) return;
    moving_ = surface;
    if (moving_.nodes == 0 || !moving_.x || !moving_.tri) return;
    if (moving_.space != Exec::kSpace)
      throw std::runtime_error(
          "moving_boundary: the surface is in another memory space than the fluid "
          "solver's; pass the body solver's arrays of the same backend");
    if (moving_.nodes != mnodes_)
      throw std::runtime_error("moving_boundary: the surface has " + std::to_string(moving_.nodes) +
                               " nodes, set_moving_samples " + std::to_string(mnodes_));
    const int n = msamples_;
    const GridView g = grid(mstart_.data());
    stages::place_samples(ex_, n, mtri_.data(), mw_.data(), moving_.tri, moving_.x, moving_.v,
                          mtmpx_.data(), moving_.v ? mtmpv_.data() : nullptr);
    stages::cell_keys(ex_, g, mtmpx_.data(), mkeys_.data(), mperm_.data(), n);
    sort_pairs(ex_, mkeys_.data(), mperm_.data(), n, key_bits());
    stages::gather(ex_, mtmpx_.data(), mx_.data(), mperm_.data(), n);
    if (moving_.v) stages::gather(ex_, mtmpv_.data(), mv_.data(), mperm_.data(), n);
    stages::invert(ex_, mperm_.data(), mslot_.data(), n);
    stages::cell_starts(ex_, mkeys_.data(), mstart_.data(), n, g.cells());
    mactive_ = n;
    const BoundaryView b = moving();
    stages::sample_psi(ex_, P_, b, mpsi_.data());
    stages::wall_rest(ex_, P_, mrest_.data(), mnb_rest_.data(), b, moving_share_);
    mimp_.zero();
  }

  FluidView view() {
    FluidView f;
    f.n = n_;
    f.x = x_.data();
    f.v = v_.data();
    f.a = a_.data();
    f.rho = rho_.data();
    f.p = p_.data();
    f.alpha = alpha_.data();
    f.kappa = kappa_.data();
    f.kappa_sum = ksum_.data();
    f.warm_div = warm_div_.data();
    f.warm_dens = warm_dens_.data();
    f.full = full_.data();
    f.gwall = tmp3_.data();  // free between the sort and the next one
    f.nb = nb_.data();
    f.id = id_.data();
    f.nbr = nbr_.data();
    f.nbr_n = nbr_n_.data();
    f.nbr_cap = nbr_cap_;
    return f;
  }

  int key_bits() const {
    int bits = 1;
    while ((1ll << bits) < model_.grid.cells()) ++bits;
    return bits;
  }

  // Counting the cells by radix sort, then re-ordering particles by cell for locality.
  void sort_particles() {
    const GridView g = grid(start_.data());
    stages::cell_keys(ex_, g, x_.data(), keys_.data(), perm_.data(), n_);
    sort_pairs(ex_, keys_.data(), perm_.data(), n_, key_bits());
    stages::gather(ex_, x_.data(), tmp3_.data(), perm_.data(), n_);
    x_.swap(tmp3_);
    stages::gather(ex_, v_.data(), tmp3_.data(), perm_.data(), n_);
    v_.swap(tmp3_);
    stages::gather(ex_, id_.data(), tmpu_.data(), perm_.data(), n_);
    id_.swap(tmpu_);
    stages::gather(ex_, p_.data(), tmpr_.data(), perm_.data(), n_);
    p_.swap(tmpr_);
    if (model_.solver == SolverKind::DFSPH) {
      stages::gather(ex_, warm_div_.data(), tmpr_.data(), perm_.data(), n_);
      warm_div_.swap(tmpr_);
      stages::gather(ex_, warm_dens_.data(), tmpr_.data(), perm_.data(), n_);
      warm_dens_.swap(tmpr_);
    }
    stages::cell_starts(ex_, keys_.data(), start_.data(), n_, g.cells());
  }

  void upload_boundary() {
    const MemSpace s = Exec::kSpace;
    const int nb = int(model_.boundary_x.size());
    bx_ = Buffer<Vec3>(s, std::max(nb, 1));
    bpsi_ = Buffer<Real>(s, std::max(nb, 1));
    for (Buffer<Real>* w :
         {&brest_, &bpw_, &brho_, &balpha_, &bkappa_, &bksum_, &bwarm_div_, &bwarm_dens_}) {
      *w = Buffer<Real>(s, std::max(nb, 1));
      w->zero();
    }
    bnb_rest_ = Buffer<int>(s, std::max(nb, 1));
    bfull_ = Buffer<int>(s, std::max(nb, 1));
    bstart_ = Buffer<std::uint32_t>(s, std::size_t(model_.grid.cells()) + 1);
    Buffer<Vec3> x(s, std::max(nb, 1));
    Buffer<Real> psi(s, std::max(nb, 1));
    Buffer<std::uint32_t> keys(s, std::max(nb, 1)), perm(s, std::max(nb, 1));
    x.upload(model_.boundary_x.data(), nb);
    psi.upload(model_.boundary_psi.data(), nb);
    const GridView g = grid(bstart_.data());
    stages::cell_keys(ex_, g, x.data(), keys.data(), perm.data(), nb);
    sort_pairs(ex_, keys.data(), perm.data(), nb, key_bits());
    stages::gather(ex_, x.data(), bx_.data(), perm.data(), nb);
    stages::gather(ex_, psi.data(), bpsi_.data(), perm.data(), nb);
    stages::cell_starts(ex_, keys.data(), bstart_.data(), nb, g.cells());
    stages::wall_rest(ex_, P_, brest_.data(), bnb_rest_.data(), boundary());
    exec_sync(ex_);
  }

  // CFL step: the particle spacing over the fastest speed (plus sound speed for WCSPH), capped
  // by dt_max; dt_free is that step before dt_limit shortens it.
  double choose_dt(double dt_limit, double& dt_free) {
    const Real v2 = stages::max_speed2(ex_, view());
    if (!(v2 < Real(3e38)))
      throw SimulationError(
          steps_, "step " + std::to_string(steps_) + " (t = " + fmt(t_) +
                      " s): a particle velocity or position is not finite (NaN); lower "
                      "simulation.dt_max or simulation.cfl, raise fluid.stiffness for WCSPH, "
                      "or use simulation.solver \"dfsph\"");
    const double vmax = std::sqrt(double(v2));
    const double c = model_.solver == SolverKind::WCSPH ? double(P_.sound_speed) : 0.0;
    double dt = model_.cfl * double(P_.spacing) / std::max(c + vmax, 1e-9);
    if (P_.viscosity > 0)
      dt = std::min(dt, 0.125 * double(P_.spacing) * P_.spacing / double(P_.viscosity));
    if (dt < model_.dt_min)
      throw SimulationError(
          steps_, "step " + std::to_string(steps_) + " (t = " + fmt(t_) +
                      " s): the flow is blowing up: the CFL time step " + fmt(dt) +
                      " s fell below simulation.dt_min = " + fmt(model_.dt_min) +
                      " s (fastest particle " + fmt(vmax) +
                      " m/s); lower simulation.dt_max, raise fluid.stiffness for WCSPH, add "
                      "fluid.viscosity, or use simulation.solver \"dfsph\"");
    dt_free = std::min(dt, model_.dt_max);
    dt = std::max(std::min(dt_free, dt_limit), 1e-12);
    dt_free = std::max(dt_free, dt);
    return dt;
  }

  // One DFSPH solve: the warm start, then projected Jacobi sweeps over fluid and wall samples
  // until their mean residual is below tol; returns the sweeps after the warm start. At least
  // kMinSweeps run, so the pressure keeps building while the mean error is still small
  // (Bender & Koschier 2017 also iterate at least twice): without them a resting column fell
  // freely until its bottom layers were compressed by several per cent.
  int solve(FluidView f, const GridView& g, const Walls& w, Real dt, Real pace, bool divergence,
            double tol) {
    const BoundaryView& b = w.fixed;
    const BoundaryView& mb = w.moving;
    stages::dfsph_warm_start(ex_, f, divergence);
    stages::wall_warm_start(ex_, b, divergence);
    if (mb.n) stages::wall_warm_start(ex_, mb, divergence);
    auto apply = [&] {
      stages::dfsph_apply(ex_, P_, f, g, w, dt);
      stages::wall_accumulate(ex_, b);
      if (mb.n) stages::wall_accumulate(ex_, mb);
    };
    apply();
    const int samples = n_ + active_walls_;
    int it = 0;
    last_error_ = 0;
    for (;; ++it) {
      double sum = stages::dfsph_source(ex_, P_, f, g, w, dt, pace, divergence) +
                   stages::wall_source(ex_, P_, f, g, b, dt, pace, divergence);
      if (mb.n) sum += stages::wall_source(ex_, P_, f, g, mb, dt, pace, divergence);
      const double err = samples ? sum / samples : 0.0;
      last_error_ = err;
      if ((err <= tol && it >= kMinSweeps) || it >= model_.max_iterations) break;
      apply();
    }
    const Real memory = divergence ? Real(1) : stages::kDfsphMemory;
    stages::dfsph_remember(ex_, f, memory * pace, divergence);
    return it;
  }

  int emit_layers(double dt) {
    int emitted = 0;
    for (std::size_t e = 0; e < model_.emitters.size(); ++e) {
      const EmitterModel& em = model_.emitters[e];
      if (t_ <= em.start || t_ - dt >= em.end) continue;
      const double active = std::min(t_, double(em.end)) - std::max(t_ - dt, double(em.start));
      travelled_[e] += em.speed * active;
      const int k = int(em.disc.size());
      while (travelled_[e] >= em.layer_spacing) {
        travelled_[e] -= em.layer_spacing;
        if (n_ + k > cap_) {
          if (!capacity_warned_)
            std::fprintf(stderr, "warning: particle capacity %d reached; emitters stop\n", cap_);
          capacity_warned_ = true;
          break;
        }
        const Vec3 origin = em.position + em.direction * Real(travelled_[e]);
        stages::emit_layer(ex_, view(), discs_[e].data(), k, n_, origin, em.direction * em.speed,
                           next_id_);
        n_ += k;
        next_id_ += std::uint32_t(k);
        emitted += k;
      }
    }
    return emitted;
  }

  static std::string fmt(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
  }

  FluidModel model_;
  SphParams P_;
  Exec ex_;
  int n_ = 0, cap_ = 0;
  double t_ = 0, last_error_ = 0;
  long steps_ = 0;
  Buffer<Vec3> x_, v_, a_, tmp3_;
  Buffer<Real> rho_, p_, alpha_, kappa_, ksum_, tmpr_;
  Buffer<Real> warm_div_, warm_dens_;  // DFSPH warm starts, follow the particles
  Buffer<int> nb_, full_;
  Buffer<std::uint32_t> nbr_;  // fluid neighbour lists of the step (FluidView::nbr)
  Buffer<int> nbr_n_;
  int nbr_cap_ = 0;
  Buffer<std::uint32_t> id_, tmpu_, keys_, perm_, start_;
  Buffer<Vec3> bx_;
  Buffer<Real> bpsi_, brest_, bpw_, brho_, balpha_, bkappa_, bksum_, bwarm_div_, bwarm_dens_;
  Buffer<int> bnb_rest_, bfull_;
  int active_walls_ = 0;  // wall samples with fluid in reach (DFSPH)
  Buffer<std::uint32_t> bstart_;
  std::vector<Buffer<Vec3>> discs_;
  std::vector<double> travelled_;
  std::uint32_t next_id_ = 0;
  bool capacity_warned_ = false;
  StepProfile prof_;
  StepHook* hook_ = nullptr;
  double dt_ = 0;  // this step's length (time_step)
  Real pace_ = 1;  // dt_ over the CFL step it shortened
  static constexpr int kMinSweeps = 2;

  // Near-surface density: the hook's proximity of this step, and the half-space integrals.
  static constexpr int kHalfSpaceSteps = 256;
  SurfaceProximity prox_;
  Buffer<Real> half_;

  // Boundary-particle coupling: per sample (original order) its triangle and weights; per
  // placed sample (sorted by cell) the wall quantities of BoundaryView and the impulse; the
  // nodes' gather lists.
  int msamples_ = 0, mnodes_ = 0, mactive_ = 0;
  Real moving_share_ = 1;  // DFSPH walls-alone share of a sample (stages::moving_rest_share)
  MovingSurface moving_;
  Buffer<int> mtri_;
  Buffer<Vec3> mw_, mx_, mv_, mtmpx_, mtmpv_, mimp_;
  Buffer<Real> mpsi_, mrest_, mpw_, mrho_, malpha_, mkappa_, mksum_, mwarm_div_, mwarm_dens_;
  Buffer<int> mnb_rest_, mfull_;
  Buffer<std::uint32_t> mkeys_, mperm_, mslot_, mstart_;
  Buffer<int> mnode_start_, mnode_sample_;
  Buffer<Real> mnode_w_;
};

}  // namespace sphfem
