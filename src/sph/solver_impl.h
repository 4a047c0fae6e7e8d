// FluidSolver over one execution backend: owns the state buffers and runs the stages of
// src/sph/stages.h in the order of one step. Included once per backend.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "sph/stages.h"
#include "sphfem/core/memory.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

using stages::BoundaryView;
using stages::FluidView;

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
    for (const EmitterModel& e : m.emitters) {
      discs_.emplace_back(s, e.disc.size());
      discs_.back().upload(e.disc.data(), e.disc.size());
      travelled_.push_back(0.0);
    }
    last_dt_ = m.dt_max;
  }

  int count() const override { return n_; }
  double time() const override { return t_; }
  long steps() const override { return steps_; }
  const Profile& profile() const override { return prof_; }
  void reset_profile() override { prof_.clear(); }
  const FluidModel& model() const override { return model_; }

  StepInfo step(double dt_limit) override {
    StepInfo info;
    const bool dfsph = model_.solver == SolverKind::DFSPH;
    timed(Phase::Neighbors, [&] { sort_particles(); });
    const GridView g = grid(start_.data());
    const BoundaryView b = boundary();
    FluidView f = view();
    timed(Phase::Density, [&] {
      stages::density(ex_, P_, f, g, b, dfsph);
      if (dfsph) {
        active_walls_ = stages::wall_density(ex_, P_, f, g, b);
        stages::dfsph_smooth_warm(ex_, P_, f, g, b, tmpr_.data());
        warm_dens_.swap(tmpr_);
        f.warm_dens = warm_dens_.data();
      }
    });
    if (dfsph) p_.zero();

    double dt_free = 0;
    const double dt = choose_dt(dt_limit, dt_free);
    const Real rdt = Real(dt);
    // How much of a full step this one is: the pace of density corrections and the weight of
    // this step in the warm starts (stages::dfsph_source, stages::dfsph_remember).
    const Real pace = Real(dt / dt_free);
    info.dt = dt;
    if (dfsph) {
      timed(Phase::Divergence, [&] {
        info.divergence_iterations = solve(f, g, b, rdt, pace, true, model_.divergence_tolerance);
      });
      timed(Phase::Forces, [&] { stages::accelerations(ex_, P_, f, g, b, false, rdt); });
      timed(Phase::Integrate, [&] { stages::kick(ex_, f, rdt); });
      timed(Phase::Pressure, [&] {
        info.pressure_iterations = solve(f, g, b, rdt, pace, false, model_.density_tolerance);
        info.density_error = last_error_;
      });
    } else {
      timed(Phase::Forces, [&] {
        stages::wall_pressure(ex_, P_, f, g, b);
        stages::accelerations(ex_, P_, f, g, b, true, rdt);
      });
      timed(Phase::Integrate, [&] { stages::kick(ex_, f, rdt); });
    }
    timed(Phase::Integrate, [&] { info.clamped = stages::drift(ex_, P_, f, rdt); });
    t_ += dt;
    ++steps_;
    last_dt_ = dt;
    timed(Phase::Emit, [&] { info.emitted = emit(dt); });
    ++prof_.steps;
    return info;
  }

  void snapshot(FluidSnapshot& out) override {
    // Densities and neighbour counts of the current positions, not of the last step's start.
    sort_particles();
    FluidView f = view();
    stages::density(ex_, P_, f, grid(start_.data()), boundary(),
                    model_.solver == SolverKind::DFSPH);
    out.n = n_;
    out.x.resize(n_);
    out.v.resize(n_);
    out.rho.resize(n_);
    out.p.resize(n_);
    out.id.resize(n_);
    out.neighbors.resize(n_);
    x_.download(out.x.data(), n_);
    v_.download(out.v.data(), n_);
    rho_.download(out.rho.data(), n_);
    p_.download(out.p.data(), n_);
    id_.download(out.id.data(), n_);
    nb_.download(out.neighbors.data(), n_);
  }

 private:
  template <class F>
  void timed(Phase ph, F&& fn) {
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
  int solve(FluidView f, const GridView& g, const BoundaryView& b, Real dt, Real pace,
            bool divergence, double tol) {
    stages::dfsph_warm_start(ex_, f, b, divergence);
    stages::dfsph_apply(ex_, P_, f, g, b, dt);
    const int samples = n_ + active_walls_;
    int it = 0;
    last_error_ = 0;
    for (;; ++it) {
      const double sum = stages::dfsph_source(ex_, P_, f, g, b, dt, pace, divergence) +
                         stages::wall_source(ex_, P_, f, g, b, dt, pace, divergence);
      const double err = samples ? sum / samples : 0.0;
      last_error_ = err;
      if ((err <= tol && it >= kMinSweeps) || it >= model_.max_iterations) break;
      stages::dfsph_apply(ex_, P_, f, g, b, dt);
    }
    const Real memory = divergence ? Real(1) : stages::kDfsphMemory;
    stages::dfsph_remember(ex_, f, memory * pace, divergence);
    return it;
  }

  int emit(double dt) {
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
  double t_ = 0, last_dt_ = 0, last_error_ = 0;
  long steps_ = 0;
  Buffer<Vec3> x_, v_, a_, tmp3_;
  Buffer<Real> rho_, p_, alpha_, kappa_, ksum_, tmpr_;
  Buffer<Real> warm_div_, warm_dens_;  // DFSPH warm starts, follow the particles
  Buffer<int> nb_, full_;
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
  Profile prof_;
  static constexpr int kMinSweeps = 2;
};

}  // namespace sphfem
