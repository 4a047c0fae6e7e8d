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

#include "sph/fluid_buffers.h"
#include "sph/moving_samples.h"
#include "sph/sample_set.h"
#include "sph/stages.h"
#include "sph/wall_lists.h"
#include "sphfem/core/memory.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

using stages::BoundaryView;
using stages::FluidView;
using stages::Walls;

template <class Exec>
class SolverT final : public FluidSolver {
 public:
  explicit SolverT(const FluidModel& m) : model_(settings(m)), P_(m.params) {
    const MemSpace s = Exec::kSpace;
    cap_ = std::max<int>(m.capacity, int(m.x0.size()));
    fluid_.allocate(s, cap_, m.params.full_neighbors, m.grid.cells(),
                    m.solver == SolverKind::DFSPH);

    n_ = int(m.x0.size());
    fluid_.x.upload(m.x0.data(), n_);
    fluid_.v.upload(m.v0.data(), n_);
    std::vector<std::uint32_t> ids(n_);
    for (int i = 0; i < n_; ++i) ids[i] = std::uint32_t(i);
    fluid_.id.upload(ids.data(), n_);
    next_id_ = std::uint32_t(n_);

    upload_tank(m);
    // The space beyond a surface filled like the tank's walls (sph/surface_density.h).
    const double layer = double(P_.spacing) / double(P_.h);
    const double lattice_mass =
        double(P_.mass) / (double(P_.rho0) * std::pow(double(P_.spacing), 3));
    const std::vector<Real> half =
        half_space_table(P_.kernel, kHalfSpaceSteps, layer, lattice_mass);
    half_ = Buffer<Real>(s, half.size());
    half_.upload(half.data(), half.size());
    moving_.set_rest_share(stages::moving_rest_share(
        half, half_space_table(P_.kernel, kHalfSpaceSteps), kHalfSpaceSteps, layer));
    for (const EmitterModel& e : m.emitters) {
      discs_.emplace_back(s, e.disc.size());
      discs_.back().upload(e.disc.data(), e.disc.size());
      travelled_.push_back(0.0);
      emitter_on_.push_back(1);
    }
  }

  int count() const override { return n_; }
  double time() const override { return t_; }
  long steps() const override { return steps_; }
  const StepProfile& profile() const override { return prof_; }
  void reset_profile() override { prof_.clear(); }
  const FluidModel& model() const override { return model_; }
  void set_hook(StepHook* hook) override { hook_ = hook; }

  void set_emitter_enabled(int e, bool enabled) override {
    emitter_on_.at(emitter_index(e)) = enabled ? 1 : 0;
  }
  bool emitter_enabled(int e) const override { return emitter_on_.at(emitter_index(e)) != 0; }

  void set_moving_samples(const std::vector<SurfaceSample>& samples, const std::vector<Tri>& tris,
                          int nodes) override {
    moving_.set(samples, tris, nodes, grid(nullptr));
  }

  // A fluid alone: the stages in Simulation::step's order, with the hook around the drift.
  StepInfo step(double dt_limit) override {
    StepInfo info;
    timed(Stage::Neighbors, [&] {
      sort(hook_ && moving_.count() ? hook_->moving_boundary(arrays()) : MovingSurface());
    });
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
    planes_laid_ = false;
    forget_wall_lists();
    moving_.place(ex_, P_, moving, key_bits());
    fluid_.sort(ex_, grid(fluid_.start.data()), n_, key_bits(), model_.solver == SolverKind::DFSPH);
    // Where the supports end, for the wall passes of this step (until drift moves the fluid).
    reached_ = fluid_.view(n_);
    stages::fluid_reach(ex_, P_, reached_);
    exec_sync(ex_);
  }

  void density(const SurfaceProximity& near) override {
    prox_ = near;
    const bool dfsph = model_.solver == SolverKind::DFSPH;
    const Walls w = walls();
    FluidView f = view();
    const GridView g = grid(fluid_.start.data());
    // The list build's scan reads the positions as planes, laid out in a (free until the
    // forces; the host only: a device scans one candidate a thread).
    if (Exec::kSpace == MemSpace::Host) {
      see_planes(f);
      stages::position_planes(ex_, f);
      planes_laid_ = true;
    }
    // Under DFSPH the density pass also takes the fluid pairs' sums of the density solve's
    // warm-start filter (stages::WarmSums), into kappa and kappa_sum, free until the divergence
    // solve, and on the host those of the divergence solve's warm-start sweep.
    stages::WarmSums warm;
    if (dfsph) {
      warm.dens_w = fluid_.kappa.data();
      warm.dens_kw = fluid_.ksum.data();
      if (fluid_.packed) warm.div_dv = fluid_.warm_dv.data();
    }
    fluid_.list_and_density(ex_, P_, f, g, w, dfsph, warm);
    if (dfsph) {
      if constexpr (Exec::kSpace == MemSpace::Host) {
        active_walls_ = tank_lists_.density(ex_, P_, f, g, w.fixed);
        if (w.moving.n) active_walls_ += moving_lists_.density(ex_, P_, f, g, w.moving);
      } else {
        active_walls_ = stages::wall_density(ex_, P_, f, g, w.fixed);
        if (w.moving.n) active_walls_ += stages::wall_density(ex_, P_, f, g, w.moving);
      }
      fluid_.p.zero();
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
    // The density solve's warm start, filtered now that the step's dt sets the rate (its fluid
    // sums are the density pass's, in kappa and kappa_sum, which the solve below takes over);
    // pressure() makes it the warm start.
    const Real rate = Real(std::min(1.0, stages::kDfsphWarmSmoothing * warm_weight()));
    stages::dfsph_smooth_warm(ex_, P_, view(), w, rate, fluid_.kappa.data(), fluid_.ksum.data(),
                              fluid_.tmpr.data());
    info.divergence_iterations = solve(view(), grid(fluid_.start.data()), w, Real(dt_), pace_, true,
                                       model_.divergence_tolerance);
    if (w.moving.n)
      stages::sample_pressure_impulse(ex_, P_, view(), grid(fluid_.start.data()), w.moving,
                                      Real(dt_), moving_.impulse());
    exec_sync(ex_);
  }

  void forces(StepInfo&) override {
    const bool wcsph = model_.solver == SolverKind::WCSPH;
    const Walls w = walls();
    FluidView f = view();
    const GridView g = grid(fluid_.start.data());
    const Real rdt = Real(dt_);
    if (wcsph) {
      // The wall samples' scans sift their candidates from the planes the density pass laid
      // out in a, until the accelerations below overwrite them.
      FluidView fp = f;
      if (planes_laid_) see_planes(fp);
      stages::wall_pressure(ex_, P_, fp, g, w.fixed);
      if (w.moving.n) stages::wall_pressure(ex_, P_, fp, g, w.moving);
    }
    planes_laid_ = false;
    // DFSPH: the fluid pairs of the density solve's warm-start sweep, summed here into tmp3
    // (FluidView::gwall, spent since wall_density) and applied by pressure().
    if (wcsph) {
      // What the pairs read of a neighbour, laid out as its records (FluidView::rec_x).
      FluidView fr = f;
      if (fluid_.see_records(fr)) stages::pair_records(ex_, P_, fr);
      stages::accelerations(ex_, P_, fr, g, w, true, rdt, nullptr, nullptr);
    } else {
      stages::accelerations(ex_, P_, f, g, w, false, rdt, fluid_.tmpr.data(), fluid_.tmp3.data());
    }
    if (w.moving.n)
      stages::sample_force_impulse(ex_, P_, f, g, w.moving, wcsph, rdt, moving_.impulse());
    stages::kick(ex_, f, rdt);
    exec_sync(ex_);
  }

  void pressure(StepInfo& info) override {
    const Walls w = walls();
    if (model_.solver == SolverKind::DFSPH) {
      // The warm start as divergence() filtered it. The smoothing keeps pace with the memory
      // (stages::kDfsphWarmSmoothing).
      fluid_.warm_dens.swap(fluid_.tmpr);
      info.pressure_iterations = solve(view(), grid(fluid_.start.data()), w, Real(dt_), pace_,
                                       false, model_.density_tolerance);
      info.density_error = last_error_;
      if (w.moving.n)
        stages::sample_pressure_impulse(ex_, P_, view(), grid(fluid_.start.data()), w.moving,
                                        Real(dt_), moving_.impulse());
    }
    moving_.to_nodes(ex_);
    exec_sync(ex_);
  }

  void drift(const DriftLimits& limits, StepInfo& info) override {
    planes_laid_ = false;
    info.clamped = stages::drift(ex_, P_, view(), Real(dt_), limits.travel, limits.surface_v);
    reached_.reached = 0;
    forget_wall_lists();
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
    a.x = fluid_.x.data();
    a.v = fluid_.v.data();
    a.id = fluid_.id.data();
    a.mass = P_.mass;
    a.radius = P_.spacing / Real(2);
    return a;
  }

  // Densities and neighbour counts of the present positions, computed on a cell-sorted copy
  // (scratch buffers only) and returned in the state's order, which stays as it is.
  void snapshot(FluidSnapshot& out, SurfaceQuery* surfaces) override {
    planes_laid_ = false;  // a takes the sorted velocities
    if (!surfaces) surfaces = hook_;
    forget_wall_lists();  // the moving samples are placed again
    const bool dfsph = model_.solver == SolverKind::DFSPH;
    const int n = n_;
    const GridView g = grid(fluid_.start.data());
    // fluid_.perm[k]: the state index of the k-th particle in cell order.
    stages::cell_keys(ex_, g, fluid_.x.data(), fluid_.keys.data(), fluid_.perm.data(), n);
    sort_pairs(ex_, fluid_.keys.data(), fluid_.perm.data(), n, key_bits());
    stages::gather(ex_, fluid_.x.data(), fluid_.tmp3.data(), fluid_.perm.data(), n);
    stages::gather(ex_, fluid_.v.data(), fluid_.a.data(), fluid_.perm.data(), n);
    stages::cell_starts(ex_, fluid_.keys.data(), fluid_.start.data(), n, g.cells());
    FluidView f = view();
    f.x = fluid_.tmp3.data();
    f.v = fluid_.a.data();
    f.p = fluid_.tmpr.data();
    f.warm_div = f.warm_dens = nullptr;
    f.gwall = nullptr;
    f.nbr_gs = nullptr;
    FluidArrays sorted = arrays();
    sorted.x = fluid_.tmp3.data();
    sorted.v = fluid_.a.data();
    sorted.id = nullptr;
    moving_.place(ex_, P_,
                  surfaces && moving_.count() ? surfaces->moving_boundary(sorted) : MovingSurface(),
                  key_bits());
    prox_ = surfaces ? surfaces->proximity(sorted) : SurfaceProximity();
    fluid_.list_and_density(ex_, P_, f, g, walls(), /*with_alpha=*/false);
    prox_ = SurfaceProximity();
    exec_sync(ex_);
    std::vector<std::uint32_t> perm(n);
    std::vector<Real> rho(n), p(n);
    std::vector<int> nb(n);
    fluid_.perm.download(perm.data(), n);
    fluid_.rho.download(rho.data(), n);
    fluid_.nb.download(nb.data(), n);
    fluid_.tmpr.download(p.data(), n);
    out.n = n;
    out.rho.resize(n);
    out.p.resize(n);
    out.neighbors.resize(n);
    fluid_.x.download(out.x, n);
    fluid_.v.download(out.v, n);
    fluid_.id.download(out.id, n);
    // DFSPH: the pressure of the last solve, in the state's order; WCSPH: the equation of state
    // at the present densities.
    if (dfsph) fluid_.p.download(out.p.data(), n);
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
    fluid_.x.download(s.x, n_);
    fluid_.v.download(s.v, n_);
    fluid_.id.download(s.id, n_);
    fluid_.warm_div.download(s.warm_div, n_);
    fluid_.warm_dens.download(s.warm_dens, n_);
  }

  void load(const FluidState& s) override {
    planes_laid_ = false;
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
    reached_.reached = 0;
    forget_wall_lists();
    t_ = s.time;
    steps_ = s.steps;
    next_id_ = s.next_id;
    capacity_warned_ = s.capacity_warned;
    travelled_ = s.emitter_travel;
    fluid_.x.upload(s.x.data(), n);
    fluid_.v.upload(s.v.data(), n);
    fluid_.id.upload(s.id.data(), n);
    fluid_.warm_div.upload(s.warm_div.data(), n);
    fluid_.warm_dens.upload(s.warm_dens.data(), n);
    fluid_.p.zero();
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

  Walls walls() {
    Walls w;
    w.fixed = tank();
    w.moving = moving_.view();
    if constexpr (Exec::kSpace == MemSpace::Host) {
      tank_lists_.attach(w.fixed);
      if (w.moving.n) moving_lists_.attach(w.moving);
    }
    if (prox_.dist && prox_.normal) {
      w.surface.dist = prox_.dist;
      w.surface.normal = prox_.normal;
      w.surface.vel = prox_.velocity;
      w.surface.dv = prox_.dv;
      w.surface.slip = prox_.slip;
    }
    w.surface.half.table = half_.data();
    w.surface.half.n = kHalfSpaceSteps;
    w.surface.half.inv_h = Real(1) / P_.h;
    return w;
  }

  FluidView view() {
    FluidView f = fluid_.view(n_);
    f.reached = reached_.reached;
    f.reach_lo = reached_.reach_lo;
    f.reach_hi = reached_.reach_hi;
    return f;
  }

  // The tank's samples, sorted into their grid once (upload_tank).
  BoundaryView tank() {
    BoundaryView b = tank_.view(tank_n_);
    b.quiet_lo = quiet_lo_;
    b.quiet_hi = quiet_hi_;
    return b;
  }

  int key_bits() const { return cell_key_bits(model_.grid.cells()); }

  // The samples' lists of their fluid neighbours hold from the density pass until the fluid
  // or the moving samples move (WallLists).
  void forget_wall_lists() {
    tank_lists_.invalidate();
    moving_lists_.invalidate();
  }

  // The model less its arrays of particles and samples, which the buffers hold from here on
  // (not kept twice: 61 B a particle in the dam break).
  static FluidModel settings(const FluidModel& m) {
    FluidModel k = m;
    std::vector<Vec3>().swap(k.x0);
    std::vector<Vec3>().swap(k.v0);
    std::vector<Vec3>().swap(k.boundary_x);
    std::vector<Real>().swap(k.boundary_psi);
    return k;
  }

  void upload_tank(const FluidModel& m) {
    const MemSpace s = Exec::kSpace;
    const int nb = int(m.boundary_x.size());
    tank_n_ = nb;
    tank_.resize(nb, grid(nullptr));
    // The tank's samples lie beyond the domain's faces: the particles away from them skip
    // the tank's scan (stages::in_quiet).
    BoundaryView quiet;
    stages::quiet_box(m.boundary_x.data(), nb, P_.clamp_lo, P_.clamp_hi, P_.h, quiet);
    quiet_lo_ = quiet.quiet_lo;
    quiet_hi_ = quiet.quiet_hi;
    Buffer<Vec3> x(s, std::max(nb, 1));
    Buffer<Real> psi(s, std::max(nb, 1));
    Buffer<std::uint32_t> keys(s, std::max(nb, 1)), perm(s, std::max(nb, 1));
    x.upload(m.boundary_x.data(), nb);
    psi.upload(m.boundary_psi.data(), nb);
    const GridView g = tank_.grid();
    stages::cell_keys(ex_, g, x.data(), keys.data(), perm.data(), nb);
    sort_pairs(ex_, keys.data(), perm.data(), nb, key_bits());
    stages::gather(ex_, x.data(), tank_.x.data(), perm.data(), nb);
    stages::gather(ex_, psi.data(), tank_.psi.data(), perm.data(), nb);
    stages::cell_starts(ex_, keys.data(), tank_.start.data(), nb, g.cells());
    stages::wall_rest(ex_, P_, tank_.rest.data(), tank_.nb_rest.data(), tank());
    exec_sync(ex_);
  }

  // Points f at the positions as planes, laid out in a (FluidView::planes).
  void see_planes(FluidView& f) {
    f.planes = &fluid_.a.data()[0].x;
    f.planes_stride = std::size_t(fluid_.cap) + 1;
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
    auto apply = [&](const Vec3* fluid_dv) {
      stages::dfsph_apply(ex_, P_, f, g, w, dt, fluid_dv);
      stages::wall_accumulate(ex_, b);
      if (mb.n) stages::wall_accumulate(ex_, mb);
    };
    // The warm start: its fluid pairs were summed by the density pass (divergence, on the
    // host) or with the forces (density). One pass over the pairs fewer a step.
    apply(divergence ? (fluid_.packed ? fluid_.warm_dv.data() : nullptr) : fluid_.tmp3.data());
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
      apply(nullptr);
    }
    stages::dfsph_remember(ex_, f, divergence ? pace : Real(warm_weight()), divergence);
    return it;
  }

  // This step's weight in the density solve's running mean (stages::kDfsphWarmTime),
  // bias-corrected: the mean starts from nothing at t = 0, so the first solves weigh more and
  // the warm start holds the water's weight after about one mean's time, not several.
  double warm_weight() const {
    const double T = stages::kDfsphWarmTime;
    const double filled = -std::expm1(-(t_ + dt_) / T);
    return std::min(1.0, dt_ / T / std::max(filled, 1e-12));
  }

  int emit_layers(double dt) {
    int emitted = 0;
    for (std::size_t e = 0; e < model_.emitters.size(); ++e) {
      const EmitterModel& em = model_.emitters[e];
      if (!emitter_on_[e] || t_ <= em.start || t_ - dt >= em.end) continue;
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

  std::size_t emitter_index(int e) const {
    if (e < 0 || std::size_t(e) >= emitter_on_.size())
      throw std::out_of_range("emitter " + std::to_string(e) + ": the scene has " +
                              std::to_string(emitter_on_.size()) +
                              " emitters (fluid.emitters), numbered from 0");
    return std::size_t(e);
  }

  static std::string fmt(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
  }

  // The state (save / load): n_, t_, steps_, next_id_, capacity_warned_, travelled_ and the
  // state buffers of fluid_. The rest is fixed by the model and set_moving_samples (tank_,
  // moving_'s samples, discs_, half_) or recomputed by every step.
  FluidModel model_;
  SphParams P_;
  Exec ex_;
  int n_ = 0, cap_ = 0;
  double t_ = 0, last_error_ = 0;
  long steps_ = 0;
  FluidBuffers fluid_;                   // state and scratch, see sph/fluid_buffers.h
  SampleSet<Exec> tank_;                 // the tank's wall samples (upload_tank)
  int tank_n_ = 0;                       // how many
  Vec3 quiet_lo_, quiet_hi_;             // BoundaryView::quiet_lo of the tank
  bool planes_laid_ = false;             // a holds the positions as planes (density() to forces)
  FluidView reached_;                    // FluidView::reach_lo of this step (sort), until drift
  MovingSamples<Exec> moving_;           // boundary-particle coupling: samples on a moving surface
  int active_walls_ = 0;                 // wall samples with fluid in reach (DFSPH)
  WallLists tank_lists_, moving_lists_;  // the host's, under DFSPH
  std::vector<Buffer<Vec3>> discs_;
  std::vector<double> travelled_;
  std::vector<std::uint8_t> emitter_on_;  // per emitter: a control input, not saved state
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
};

}  // namespace sphfem
