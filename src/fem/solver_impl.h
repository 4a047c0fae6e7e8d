// BodySolver over one execution backend: owns the state buffers and runs the stages of
// src/fem/stages.h in the order of one step. Included once per backend.
#pragma once

#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "fem/coarse.h"
#include "fem/stages.h"
#include "fem/wall_stages.h"
#include "sphfem/core/memory.h"
#include "sphfem/fem/solver.h"

namespace sphfem {

template <class Exec>
class BodySolverT final : public BodySolver {
 public:
  explicit BodySolverT(std::shared_ptr<const BodiesModel> model) : model_(std::move(model)) {
    const BodiesModel& m = *model_;
    const MemSpace s = Exec::kSpace;
    n_ = m.nodes;
    ne_ = m.elements;
    upload(tets_, m.tets);
    upload(surface_, m.surface);
    upload(grad_, m.grad);
    upload(mu_vol_, m.mu_vol);
    upload(lambda_vol_, m.lambda_vol);
    upload(beta_, m.beta);
    upload(mass_, m.mass);
    upload(alpha_, m.alpha);
    upload(pinned_, m.pinned);
    upload(inc_start_, m.inc_start);
    upload(inc_, m.inc);
    upload(x_, m.x0);
    upload(v_, m.v0);
    for (Buffer<Vec3>* b :
         {&dv_, &delta_, &u_, &b_, &r_, &z_, &p_, &q_, &impulse_, &staging_, &wall_f_})
      *b = Buffer<Vec3>(s, n_);
    for (Buffer<Vec3>* b : {&dv_, &impulse_}) b->zero();
    pinv_ = Buffer<fem::Sym3>(s, n_);
    wall_mask_ = Buffer<std::uint8_t>(s, n_);
    wall_mask_.zero();
    P_ = Buffer<Vec3>(s, std::size_t(3) * ne_);
    fe_ = Buffer<Vec3>(s, std::size_t(4) * ne_);
    std::vector<Quat> q0(ne_, Quat::identity());
    upload(rot_, q0);
    rot_scratch_ = Buffer<Quat>(s, ne_);
    if (s == MemSpace::Host && m.settings.two_level)
      coarse_ = std::make_unique<fem::CoarseLevel>(m, fem::CoarseLevel::kCells);
  }

  const BodiesModel& model() const override { return *model_; }
  int node_count() const override { return n_; }
  double time() const override { return t_; }
  long steps() const override { return steps_; }
  const BodyProfile& profile() const override { return prof_; }
  void reset_profile() override { prof_ = BodyProfile(); }

  BodyStepInfo step(double dt_in) override {
    const FemSettings& S = model_->settings;
    const Real dt = Real(dt_in);
    const fem::ElementView e = elements();
    const fem::NodeView nv = nodes();
    const bool impulses = has_impulses_ || impulses_exposed_;
    BodyStepInfo info;
    for (int k = 0; k < S.newton_iterations; ++k) {
      // The velocity the step linearises about: v, then v + dv for Newton corrections.
      const Vec3* u = v_.data();
      if (k > 0) {
        fem::add(ex_, n_, v_.data(), dv_.data(), u_.data());
        u = u_.data();
      }
      timed(prof_.ms_rotations, [&] {
        fem::rotations(ex_, e, x_.data(), u, dt, rot_.data(), rot_.data(), P_.data(),
                       S.rotation_iterations, false);
      });
      timed(prof_.ms_assemble, [&] {
        fem::preconditioner(ex_, e, nv, P_.data(), dt, pinv_.data());
        // The coarse operator follows the rotations and dt; a few steps old, or for a step a
        // little shorter, it still preconditions (any symmetric positive definite one does),
        // so it is refactored every kEvery steps or when dt changed by a quarter. It is a
        // cache, not state: a resumed run refactors at once, so it matches the uninterrupted
        // one to the CG tolerance, not bit for bit.
        if (coarse_ && k == 0 &&
            (coarse_age_ >= fem::CoarseLevel::kEvery || !(dt < Real(1.25) * coarse_dt_) ||
             !(dt > Real(0.75) * coarse_dt_))) {
          coarse_dt_ = dt;
          coarse_age_ = 0;
          coarse_->factor(model_->tets, x_.data(), P_.data(), mu_vol_.data(), lambda_vol_.data(),
                          beta_.data(), nv.mass, nv.alpha, dt, held_ ? wall_mask_.data() : nullptr);
        }
        fem::element_forces(ex_, e, x_.data(), u, dt, P_.data(), fe_.data());
        fem::assemble_rhs(ex_, nv, fe_.data(), u, has_forces_ ? fext_.data() : kNone,
                          impulses ? impulse_.data() : kNone, k > 0 ? dv_.data() : kNone,
                          Vec3(S.gravity), dt, b_.data());
      });
      timed(prof_.ms_solve, [&] {
        if (k == 0) {
          solve_with_walls(dt, info);
          warm_ = true;
        } else {
          solve(dt, delta_, false, info, held_ ? wall_mask_.data() : nullptr);
          fem::accumulate(ex_, n_, delta_.data(), dv_.data());
        }
      });
    }
    timed(prof_.ms_integrate, [&] {
      fem::integrate(ex_, nv, dv_.data(), dt, x_.data(), v_.data());
      if (S.box)
        info.contacts = fem::collide_box(ex_, n_, Vec3(S.box_lo), Vec3(S.box_hi), Real(S.friction),
                                         x_.data(), v_.data());
      if (impulses) impulse_.zero();
      has_impulses_ = false;
    });
    t_ += dt_in;
    last_dt_ = dt;
    ++coarse_age_;
    ++steps_;
    ++prof_.steps;
    prof_.cg_iterations += info.cg_iterations;
    return info;
  }

  void snapshot(BodySnapshot& out) override {
    out.n = n_;
    out.x.resize(n_);
    out.v.resize(n_);
    x_.download(out.x.data(), n_);
    v_.download(out.v.data(), n_);
  }

  double kinetic_energy() override { return fem::kinetic_energy(ex_, nodes(), v_.data()); }

  double elastic_energy() override {
    return fem::elastic_energy(ex_, elements(), x_.data(), rot_.data(), kQueryIterations);
  }

  void add_node_impulses(const std::vector<Vec3>& J) override {
    check_size(J.size(), "add_node_impulses");
    staging_.upload(J.data(), n_);
    fem::accumulate(ex_, n_, staging_.data(), impulse_.data());
    exec_sync(ex_);
    has_impulses_ = true;
  }

  void set_node_forces(const std::vector<Vec3>& f) override {
    has_forces_ = !f.empty();
    if (!has_forces_) return;
    check_size(f.size(), "set_node_forces");
    fext_ = Buffer<Vec3>(Exec::kSpace, n_);
    fext_.upload(f.data(), n_);
  }

  void set_positions(const std::vector<Vec3>& x) override {
    check_size(x.size(), "set_positions");
    x_.upload(x.data(), n_);
    fem::rotations(ex_, elements(), x_.data(), kNone, Real(0), rot_.data(), rot_.data(), P_.data(),
                   kQueryIterations, true);
    exec_sync(ex_);
  }

  void set_velocities(const std::vector<Vec3>& v) override {
    check_size(v.size(), "set_velocities");
    v_.upload(v.data(), n_);
    dv_.zero();  // the last velocity change is no longer a useful CG start
  }

  void set_nodes(const std::vector<int>& nodes, const std::vector<Vec3>& x,
                 const std::vector<Vec3>& v) override {
    const std::size_t k = nodes.size();
    if (x.size() != k || v.size() != k)
      throw std::invalid_argument("set_nodes: " + std::to_string(k) + " nodes, " +
                                  std::to_string(x.size()) + " positions and " +
                                  std::to_string(v.size()) + " velocities");
    for (int i : nodes)
      if (i < 0 || i >= n_) throw std::invalid_argument("set_nodes: node out of range");
    if (k == 0) return;
    Buffer<int> idx(Exec::kSpace, k);
    Buffer<Vec3> bx(Exec::kSpace, k), bv(Exec::kSpace, k);
    idx.upload(nodes.data(), k);
    bx.upload(x.data(), k);
    bv.upload(v.data(), k);
    const int* I = idx.data();
    const Vec3 *X = bx.data(), *V = bv.data();
    Vec3 *xs = x_.data(), *vs = v_.data();
    parallel_for(ex_, int(k), [=] SPHFEM_LAMBDA(int j) {
      xs[I[j]] = X[j];
      vs[I[j]] = V[j];
    });
    exec_sync(ex_);
  }

  void elastic_forces(std::vector<Vec3>& f) override {
    const fem::ElementView e = elements();
    fem::rotations(ex_, e, x_.data(), kNone, Real(0), rot_.data(), rot_scratch_.data(), P_.data(),
                   kQueryIterations, false);
    fem::element_forces(ex_, e, x_.data(), kNone, Real(0), P_.data(), fe_.data());
    // Gather with no mass, gravity or pinning: the raw elastic force on every node.
    fem::NodeView nv = nodes();
    nv.pinned = zero_flags();
    fem::assemble_rhs(ex_, nv, fe_.data(), v_.data(), kNone, kNone, kNone, Vec3(), Real(1),
                      b_.data());
    f.resize(n_);
    b_.download(f.data(), n_);
  }

  void save(BodyState& s) const override {
    s.nodes = n_;
    s.elements = ne_;
    s.time = t_;
    s.steps = steps_;
    s.warm = warm_;
    x_.download(s.x, n_);
    v_.download(s.v, n_);
    dv_.download(s.dv, n_);
    impulse_.download(s.impulse, n_);
    rot_.download(s.rotation, ne_);
  }

  void load(const BodyState& s) override {
    const std::size_t n = std::size_t(n_), ne = std::size_t(ne_);
    if (s.nodes != n_ || s.elements != ne_ || s.x.size() != n || s.v.size() != n ||
        s.dv.size() != n || s.impulse.size() != n || s.rotation.size() != ne)
      throw std::invalid_argument("body state: " + std::to_string(s.nodes) + " nodes and " +
                                  std::to_string(s.elements) + " elements, the model has " +
                                  std::to_string(n_) + " and " + std::to_string(ne_));
    t_ = s.time;
    steps_ = s.steps;
    warm_ = s.warm;
    x_.upload(s.x.data(), n);
    v_.upload(s.v.data(), n);
    dv_.upload(s.dv.data(), n);
    impulse_.upload(s.impulse.data(), n);
    rot_.upload(s.rotation.data(), ne);
    // Waiting impulses go into the next step, as they would have.
    has_impulses_ = false;
    for (const Vec3& j : s.impulse)
      if (j.x != Real(0) || j.y != Real(0) || j.z != Real(0)) has_impulses_ = true;
    exec_sync(ex_);
  }

  void apply_step_operator(const Vec3* p, Vec3* q) override {
    fem::element_stiffness(ex_, elements(), p, P_.data(), last_dt_, fe_.data());
    fem::apply_nodes(ex_, response_nodes(), fe_.data(), p, last_dt_, q);
    exec_sync(ex_);
  }

  void step_operator_diagonal(Real* blocks) override {
    fem::diagonal_blocks(ex_, elements(), response_nodes(), P_.data(), last_dt_, blocks);
    exec_sync(ex_);
  }

  void add_velocity_change(const Vec3* dv) override {
    const std::uint8_t* pinned = pinned_.data();
    Vec3* v = v_.data();
    Vec3* x = x_.data();
    const Real dt = last_dt_;
    parallel_for(ex_, n_, [=] SPHFEM_LAMBDA(int i) {
      if (pinned[i]) return;
      v[i] += dv[i];
      x[i] += dv[i] * dt;
    });
    exec_sync(ex_);
  }

  double last_dt() const override { return double(last_dt_); }

  BodyArrays arrays() override {
    BodyArrays a;
    a.space = Exec::kSpace;
    a.nodes = n_;
    a.triangles = int(model_->surface.size());
    a.x = x_.data();
    a.v = v_.data();
    a.impulse = impulse_.data();
    a.mass = mass_.data();
    a.pinned = pinned_.data();
    a.surface = surface_.data();
    impulses_exposed_ = true;  // the caller may write impulses directly, any step from now on
    return a;
  }

 private:
  static constexpr int kQueryIterations = 30;
  static constexpr const Vec3* kNone = nullptr;  // an absent optional array

  template <class T>
  void upload(Buffer<T>& b, const std::vector<T>& v) {
    b = Buffer<T>(Exec::kSpace, v.size());
    b.upload(v.data(), v.size());
  }

  void check_size(std::size_t got, const char* what) const {
    if (got != std::size_t(n_))
      throw std::invalid_argument(std::string(what) + ": " + std::to_string(got) + " values for " +
                                  std::to_string(n_) + " nodes");
  }

  template <class F>
  void timed(double& ms, F&& fn) {
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    exec_sync(ex_);
    ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }

  fem::ElementView elements() const {
    fem::ElementView e;
    e.n = ne_;
    e.tet = tets_.data();
    e.grad = grad_.data();
    e.mu_vol = mu_vol_.data();
    e.lambda_vol = lambda_vol_.data();
    e.beta = beta_.data();
    return e;
  }

  fem::NodeView nodes() const {
    fem::NodeView nv;
    nv.n = n_;
    nv.mass = mass_.data();
    nv.alpha = alpha_.data();
    nv.pinned = pinned_.data();
    nv.inc_start = inc_start_.data();
    nv.inc = inc_.data();
    return nv;
  }

  // The nodes without mass-proportional damping (the response to a contact impulse).
  fem::NodeView response_nodes() {
    fem::NodeView nv = nodes();
    if (zero_alpha_.size() != std::size_t(n_)) upload(zero_alpha_, std::vector<Real>(n_, Real(0)));
    nv.alpha = zero_alpha_.data();
    return nv;
  }

  const std::uint8_t* zero_flags() {
    if (zero_flags_.size() != std::size_t(n_)) {
      upload(zero_flags_, std::vector<std::uint8_t>(n_, 0));
    }
    return zero_flags_.data();
  }

  // q = A p, returns p . q.
  double apply(Real dt, const Vec3* p, Vec3* q) {
    fem::element_stiffness(ex_, elements(), p, P_.data(), dt, fe_.data());
    return fem::apply_nodes(ex_, nodes(), fe_.data(), p, dt, q);
  }

  // The solve of a step with the tank's walls as constraints (fem/wall_stages.h). Nodes
  // resting on a wall or heading out of the box are held on it; the force the last step's
  // velocity change predicts (A dv - b) lets go walls that would pull and gives friction in
  // the right-hand side. After the solve, nodes now heading out are held and the step is solved
  // again (warm-started, friction from the force just found); a wall found pulling only then
  // lets go without another solve (the node stays on it this step, the next prediction frees
  // it). A resting body needs one solve, not two. A step that touches no wall is the plain
  // solve; what the last solve still sends out of the box, the last-resort projection puts back.
  void solve_with_walls(Real dt, BodyStepInfo& info) {
    const FemSettings& S = model_->settings;
    held_ = false;
    if (!S.box) {
      solve(dt, dv_, warm_, info);
      return;
    }
    const fem::NodeView nv = nodes();
    const Vec3 lo(S.box_lo), hi(S.box_hi);
    const fem::WallBox box{lo, hi, Real(1e-5) * norm(hi - lo)};
    std::uint8_t* mask = wall_mask_.data();
    Vec3* fr = u_.data();  // the friction in b_; u_ is free until the Newton corrections
    u_.zero();
    held_ = fem::hold_walls(ex_, nv, x_.data(), v_.data(), kNone, box, dt, mask, dv_.data()) > 0;
    const bool predicted = held_ && warm_;
    if (predicted) {
      apply(dt, dv_.data(), q_.data());
      fem::wall_force(ex_, n_, q_.data(), b_.data(), wall_f_.data());
      fem::hold_walls(ex_, nv, x_.data(), v_.data(), wall_f_.data(), box, dt, mask, dv_.data());
      info.held = fem::wall_friction(ex_, nv, mask, wall_f_.data(), v_.data(), dv_.data(),
                                     Real(S.friction), fr, b_.data());
    }
    solve(dt, dv_, warm_ || held_, info, held_ ? mask : nullptr);
    if (held_) {
      apply(dt, dv_.data(), q_.data());
      fem::wall_force(ex_, n_, q_.data(), b_.data(), wall_f_.data());
    }
    const int changed =
        fem::hold_walls(ex_, nv, x_.data(), v_.data(), wall_f_.data(), box, dt, mask, dv_.data());
    if (changed == 0 && (!held_ || predicted)) return;
    if (!held_) wall_f_.zero();  // nodes held from now on: no normal impulse known yet
    held_ = true;
    info.held = fem::wall_friction(ex_, nv, mask, wall_f_.data(), v_.data(), dv_.data(),
                                   Real(S.friction), fr, b_.data());
    solve(dt, dv_, true, info, mask);
  }

  // Preconditioned CG on A x = b, from x's current value when `warm` (the last step's
  // velocity change), else from zero. Adds its iterations to info. With a wall mask, the held
  // components of x keep their values (filtered CG) and a warm start is always kept.
  void solve(Real dt, Buffer<Vec3>& xb, bool warm, BodyStepInfo& info,
             const std::uint8_t* mask = nullptr) {
    const FemSettings& S = model_->settings;
    Vec3* x = xb.data();
    // |b|^2 in the preconditioner's norm, the scale the tolerance is relative to.
    const double bb = cg_start(kNone, nullptr);
    if (!(bb > 0.0) && !(mask && bb == 0.0)) {
      xb.zero();
      if (!(bb == 0.0)) throw_not_finite();
      return;
    }
    double rz = bb;
    if (warm) {
      apply(dt, x, q_.data());
      rz = cg_start(q_.data(), mask);
      if (!(rz < bb) && !mask) {  // a worse start than zero: begin from zero
        xb.zero();
        rz = cg_start(kNone, nullptr);
      }
    } else {
      xb.zero();
      if (mask) rz = cg_start(kNone, mask);
    }
    const double target = S.cg_tolerance * S.cg_tolerance * bb;
    int it = 0;
    while (rz > target && it < S.cg_max_iterations) {
      const double pq = apply(dt, p_.data(), q_.data());
      if (!(pq > 0.0)) break;  // converged to round-off, or a non-finite state
      double rz_new = fem::cg_update(ex_, n_, Real(rz / pq), p_.data(), q_.data(), pinv_.data(), x,
                                     r_.data(), z_.data(), mask);
      if (coarse_) rz_new += coarse_->add(r_.data(), z_.data(), nullptr, mask);
      ++it;
      if (rz_new > target) fem::cg_direction(ex_, n_, Real(rz_new / rz), z_.data(), p_.data());
      rz = rz_new;
    }
    if (!std::isfinite(rz)) throw_not_finite();
    info.cg_iterations += it;
    info.cg_residual = std::sqrt(rz / bb);
  }

  // CG's start (fem::cg_start) from r = b - q (q null: x = 0), with the coarse level's part of
  // z and p when there is one; returns r . z.
  double cg_start(const Vec3* q, const std::uint8_t* mask) {
    double rz =
        fem::cg_start(ex_, n_, b_.data(), q, pinv_.data(), r_.data(), z_.data(), p_.data(), mask);
    if (coarse_) rz += coarse_->add(r_.data(), z_.data(), p_.data(), mask);
    return rz;
  }

  [[noreturn]] void throw_not_finite() const {
    throw std::runtime_error("FEM step " + std::to_string(steps_) +
                             ": the body state is not finite (NaN); lower the time step, "
                             "raise fem cg_max_iterations, or soften the material");
  }

  std::shared_ptr<const BodiesModel> model_;
  Exec ex_;
  int n_ = 0, ne_ = 0;
  double t_ = 0;
  Real last_dt_ = 0;
  long steps_ = 0;
  bool warm_ = false, has_forces_ = false, has_impulses_ = false, impulses_exposed_ = false;
  bool held_ = false;  // some node is held by a wall in this step's solve
  Buffer<std::uint8_t> wall_mask_;
  Buffer<Vec3> wall_f_;
  Buffer<Tet> tets_;
  Buffer<Tri> surface_;
  Buffer<Vec3> grad_;
  Buffer<Real> mu_vol_, lambda_vol_, beta_, mass_, alpha_, zero_alpha_;
  Buffer<std::uint8_t> pinned_, zero_flags_;
  Buffer<int> inc_start_, inc_;
  Buffer<Vec3> x_, v_, dv_, delta_, u_, b_, r_, z_, p_, q_, impulse_, staging_, fext_;
  Buffer<fem::Sym3> pinv_;
  std::unique_ptr<fem::CoarseLevel> coarse_;  // host only, when the settings ask for it
  Real coarse_dt_ = 0;                        // the dt of the last factor (0: none yet)
  int coarse_age_ = 0;                        // steps since it
  Buffer<Vec3> P_, fe_;
  Buffer<Quat> rot_, rot_scratch_;
  BodyProfile prof_;
};

}  // namespace sphfem
