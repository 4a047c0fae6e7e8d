// RayCoupling over one execution backend (include/sphfem/couple/ray_coupling.h). Included
// once per backend, like the solvers.
#pragma once

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "core/node_sums.h"
#include "sphfem/collide/bvh.h"
#include "sphfem/core/memory.h"
#include "sphfem/couple/coupler.h"
#include "sphfem/couple/ray_coupling.h"
#include "sphfem/fem/model.h"
#include "sphfem/fem/solver.h"

namespace sphfem {

// The bodies' step operator, for the joint exchange (couple/coupler.h).
class BodyOperator final : public NodeOperator {
 public:
  explicit BodyOperator(BodySolver* b) : b_(b) {}
  int nodes() const override { return b_ ? b_->node_count() : 0; }
  void apply(const Vec3* p, Vec3* q) override { b_->apply_step_operator(p, q); }
  void diagonal(Real* blocks) override { b_->step_operator_diagonal(blocks); }
  void add_velocity(const Vec3* dv) override { b_->add_velocity_change(dv); }

 private:
  BodySolver* b_;
};

template <class Exec>
class RayCouplingT final : public RayCoupling {
 public:
  RayCouplingT(const RayCouplingSettings& s, BodySolver* bodies, Backend backend)
      : set_(s), bodies_(bodies), coupler_(make_coupler(backend)) {
    const MemSpace sp = Exec::kSpace;
    for (Buffer<int>* b : {&face_, &tank_face_, &crossing_side_}) *b = Buffer<int>(sp);
    for (Buffer<Real>* b : {&t_, &u_, &v_, &len_, &tank_t_, &tank_u_, &tank_v_, &tank_len_})
      *b = Buffer<Real>(sp);
    for (Buffer<Real>* b : {&near_dist_, &near_u_, &near_v_, &near_slip_, &near_push_, &bias_})
      *b = Buffer<Real>(sp);
    near_face_ = Buffer<int>(sp);
    for (Buffer<Vec3>* b : {&near_n_, &near_vel_, &near_dv_}) *b = Buffer<Vec3>(sp);
    x_pre_ = Buffer<Vec3>(sp);
    rel_ = Buffer<Vec3>(sp);
    if (bodies_) {
      const BodyArrays a = bodies_->arrays();
      if (a.triangles > 0) {
        x_old_ = Buffer<Vec3>(sp, std::size_t(a.nodes));
        body_bvh_.build(ex_, a.x, a.surface, a.triangles);
        body_tris_ = a.triangles;
      }
      if (s.body.size() != bodies_->model().bodies.size())
        throw std::invalid_argument("RayCoupling: one ContactCoeffs per body is needed");
      // Each face's slip coefficient, for the near-surface drag.
      const std::vector<int>& off = bodies_->model().tri_offset;
      std::vector<Real> slip(std::size_t(std::max(a.triangles, 1)), Real(1));
      for (std::size_t b = 0; b + 1 < off.size() && b < s.body.size(); ++b)
        for (int f = off[b]; f < off[b + 1]; ++f) slip[std::size_t(f)] = s.body[b].slip;
      face_slip_ = Buffer<Real>(sp, slip.size());
      face_slip_.upload(slip.data(), slip.size());
    }
    if (s.rays && (s.tank || !s.obstacle_tris.empty())) build_statics();
    stats_.body_impulse.assign(s.body.size(), Vec3d());
  }

  void bodies_moved() override {
    if (body_tris_ == 0) return;
    const BodyArrays a = bodies_->arrays();
    body_bvh_.rebuild(ex_, a.x);
    body_bvh_.refit(ex_, a.x, a.x);
    exec_sync(ex_);
  }

  void move_obstacles(const std::vector<Vec3>& x_start, const std::vector<Vec3>& x_end,
                      double dt) override {
    const int n = int(x_end.size());
    if (tank_tris_ == 0 || n == 0 || obstacle_base_ + n != static_nodes_ || !(dt > 0)) return;
    if (!statics_move_) {
      tank_x_old_ = Buffer<Vec3>(Exec::kSpace, std::size_t(static_nodes_));
      static_vel_ = Buffer<Vec3>(Exec::kSpace, std::size_t(static_nodes_));
      copy(tank_x_old_.data(), tank_x_.data(), static_nodes_);  // the tank's corners
      exec_sync(ex_);
      statics_move_ = true;
    }
    tank_x_old_.upload(x_start.data(), x_start.size(), std::size_t(obstacle_base_));
    tank_x_.upload(x_end.data(), x_end.size(), std::size_t(obstacle_base_));
    const Vec3 *x0 = tank_x_old_.data(), *x1 = tank_x_.data();
    Vec3* vel = static_vel_.data();
    const Real rdt = Real(1) / Real(dt);
    parallel_for(ex_, static_nodes_, [=] SPHFEM_LAMBDA(int i) { vel[i] = (x1[i] - x0[i]) * rdt; });
    for (SurfaceBvh<Exec>* b : {&tank_bvh_, &solid_bvh_}) {
      if (b == &solid_bvh_ && solid_tris_ == 0) continue;
      b->refit(ex_, x0, x1);
      if (b->quality(ex_) > set_.rebuild_quality) {
        b->rebuild(ex_, x1);
        b->refit(ex_, x0, x1);
        ++stats_.rebuilds;
      }
    }
    exec_sync(ex_);
  }

  const RayCouplingStats& stats() const override { return stats_; }
  void reset_stats() override {
    stats_ = RayCouplingStats();
    stats_.body_impulse.assign(set_.body.size(), Vec3d());
  }

  // The baseline's samples ride on the bodies' surface as it is at the start of the step; the
  // fluid's impulse on them goes straight into the nodes' impulse array.
  MovingSurface moving_boundary(const FluidArrays&) override {
    MovingSurface m;
    if (set_.rays || body_tris_ == 0) return m;
    const BodyArrays a = bodies_->arrays();
    m.space = Exec::kSpace;
    m.nodes = a.nodes;
    m.tri = a.surface;
    m.x = a.x;
    m.v = a.v;
    m.impulse = a.impulse;
    return m;
  }

  SurfaceProximity proximity(const FluidArrays& f) override {
    SurfaceProximity p;
    near_n_active_ = 0;
    if (!set_.near_surface || (body_tris_ == 0 && solid_tris_ == 0) || f.n == 0) return p;
    const int n = f.n;
    grow(n);
    if (body_tris_ > 0) {
      body_proximity(f);
    } else {
      int* face = near_face_.data();
      Real* slip = near_slip_.data();
      Vec3 *nrm = near_n_.data(), *dv = near_dv_.data();
      parallel_for(ex_, n, [=] SPHFEM_LAMBDA(int i) {
        face[i] = -1;
        slip[i] = Real(1);
        nrm[i] = Vec3();
        dv[i] = Vec3();
      });
    }
    if (solid_tris_ > 0) solid_proximity(f);
    exec_sync(ex_);
    near_n_active_ = n;
    near_n_step_ = n;
    p.dist = near_dist_.data();
    p.normal = near_n_.data();
    p.velocity = near_vel_.data();
    p.dv = near_dv_.data();
    p.slip = near_slip_.data();
    return p;
  }

  // Public only because nvcc does not allow device lambdas in private member functions.

  // Each particle's closest body face within the support (near_face_, -1: none).
  void body_proximity(const FluidArrays& f) {
    const int n = f.n;
    // No refit: the build, and each step's refit over x_old -> x, already bound the bodies
    // where they are now (they move only in the fem stage).
    const BodyArrays a = bodies_->arrays();
    int* face = near_face_.data();
    Real *dist = near_dist_.data(), *u = near_u_.data(), *v = near_v_.data();
    Vec3 *nrm = near_n_.data(), *vel = near_vel_.data(), *dv = near_dv_.data();
    int* side = tank_face_.data();  // free until before_drift
    Vec3* point = rel_.data();      // likewise
    closest_points(ex_, body_bvh_, a.x, n, f.x, set_.support,
                   ClosestHits{face, dist, point, side, u, v});
    const Vec3* px = f.x;
    const Vec3* nx = a.x;
    const Vec3* nv = a.v;
    const Tri* tris = a.surface;
    const Real tiny = Real(1e-6) * set_.support;
    Real* slip = near_slip_.data();
    const Real* face_slip = face_slip_.data();
    parallel_for(ex_, n, [=] SPHFEM_LAMBDA(int i) {
      dv[i] = Vec3();
      nrm[i] = Vec3();
      slip[i] = Real(1);
      if (face[i] < 0) return;
      slip[i] = face_slip[face[i]];
      // The normal points from the surface to the particle; a particle inside a body (or on
      // its surface) is pushed out along the outward face normal from the surface itself.
      const Tri t = tris[face[i]];
      const Real w0 = Real(1) - u[i] - v[i];
      Vec3 d = px[i] - point[i];
      const Real l = norm(d);
      if (side[i] > 0 && l > tiny) {
        nrm[i] = d / l;
      } else {
        nrm[i] = couple::face_normal(nx[t.v[0]], nx[t.v[1]], nx[t.v[2]]);
        dist[i] = Real(0);
      }
      vel[i] = nv[t.v[0]] * w0 + nv[t.v[1]] * u[i] + nv[t.v[2]] * v[i];
    });
  }

  // The closed obstacles bound solids as bodies do: a particle whose closest surface within
  // the support is one of theirs (nearer than any body's) gets it for the near-surface
  // density, with near_face_ = -1, so that its pressure goes to no node (infinite mass).
  void solid_proximity(const FluidArrays& f) {
    const int n = f.n;
    int *sface = solid_face_.data(), *sside = solid_side_.data();
    Real *sdist = solid_dist_.data(), *su = solid_u_.data(), *sv = solid_v_.data();
    Vec3* spoint = solid_point_.data();
    const Vec3* sx = tank_x_.data();
    closest_points(ex_, solid_bvh_, sx, n, f.x, set_.support,
                   ClosestHits{sface, sdist, spoint, sside, su, sv});
    int* face = near_face_.data();
    Real *dist = near_dist_.data(), *slip = near_slip_.data();
    Vec3 *nrm = near_n_.data(), *vel = near_vel_.data(), *dv = near_dv_.data();
    const Vec3* px = f.x;
    const Tri* tris = solid_tri_.data();
    const Real* face_slip = solid_slip_.data();
    const Vec3* sxv = statics_move_ ? static_vel_.data() : nullptr;
    const Real tiny = Real(1e-6) * set_.support;
    parallel_for(ex_, n, [=] SPHFEM_LAMBDA(int i) {
      if (sface[i] < 0 || (face[i] >= 0 && dist[i] <= sdist[i])) return;
      const Tri t = tris[sface[i]];
      face[i] = -1;
      dv[i] = Vec3();
      slip[i] = face_slip[sface[i]];
      const Vec3 d = px[i] - spoint[i];
      const Real l = norm(d);
      if (sside[i] > 0 && l > tiny) {
        nrm[i] = d / l;
        dist[i] = sdist[i];
      } else {
        nrm[i] = couple::face_normal(sx[t.v[0]], sx[t.v[1]], sx[t.v[2]]);
        dist[i] = Real(0);
      }
      const Real w0 = Real(1) - su[i] - sv[i];
      vel[i] = sxv ? sxv[t.v[0]] * w0 + sxv[t.v[1]] * su[i] + sxv[t.v[2]] * sv[i] : Vec3();
    });
  }

  void before_bodies(const FluidArrays& f) override {
    ++stats_.steps;
    if (body_tris_ == 0) near_n_active_ = 0;  // the solids' pressure goes to no node
    push_in_exchange_ = near_n_active_ > 0 && set_.rays && implicit_exchange_usable();
    if (near_n_active_ > 0) return_surface_pressure(f);
    near_n_active_ = 0;
    if (!bodies_) return;
    collect_body_impulse();
    const BodyArrays a = bodies_->arrays();
    if (body_tris_ > 0) copy(x_old_.data(), a.x, a.nodes);
    exec_sync(ex_);
  }

  DriftLimits cast(const FluidArrays& f, double dt) override {
    if (!set_.rays) return baseline_cast(f);
    const int n = f.n;
    grow(n);
    const Real rdt = Real(dt);
    const Real skin = set_.skin;
    if (body_tris_ > 0) {
      const BodyArrays a = bodies_->arrays();
      refit_bodies();
      // Front faces only: a particle inside a body (an inverted element) is let out.
      cast_moving(ex_, body_bvh_, x_old_.data(), a.x, n, f.x, f.v, rdt, skin,
                  SegmentHits{face_.data(), t_.data(), u_.data(), v_.data(), len_.data(), nullptr},
                  /*face_offset=*/0, /*merge=*/false, /*front_only=*/true);
    } else {
      fill_no_hit(n);
    }
    if (tank_tris_ > 0) {
      const Vec3* from = statics_move_ ? tank_x_old_.data() : tank_x_.data();
      cast_moving(ex_, tank_bvh_, from, tank_x_.data(), n, f.x, f.v, rdt, skin,
                  SegmentHits{tank_face_.data(), tank_t_.data(), tank_u_.data(), tank_v_.data(),
                              tank_len_.data(), nullptr});
      merge_tank_hits(n);
    }
    surfaces_ = surfaces();
    const DriftLimits d = coupler_->travel(hits(), f, surfaces_, skin, dt);
    // The positions before the drift, for the leak check after it.
    if (body_tris_ > 0 || statics_move_) copy(x_pre_.data(), f.x, n);
    exec_sync(ex_);
    return d;
  }

  void fix_contacts(const FluidArrays& f) override {
    if (set_.rays) coupler_->push_out(hits(), f, surfaces_, set_.skin);
    // Obstacles on a path sweep through the fluid; either side of their faces is a front.
    if (statics_move_)
      stats_.crossed += resolve_crossings(f, 4, tank_bvh_, tank_x_old_.data(), tank_x_.data(),
                                          tank_tri_.data(), /*two_sided=*/true);
    // The baseline only counts.
    if (body_tris_ > 0) {
      const BodyArrays a = bodies_->arrays();
      stats_.crossed += resolve_crossings(f, set_.rays ? 4 : 1, body_bvh_, x_old_.data(), a.x,
                                          a.surface, /*two_sided=*/false);
    }
  }

  void exchange(const FluidArrays& f) override {
    if (!set_.rays) return;
    // The impulse lands in the nodes' array; collect_body_impulse counts it per body.
    const bool near = near_n_step_ == f.n && body_tris_ > 0 && set_.implicit_exchange;
    near_n_step_ = 0;
    if (near) add_near_contacts(f);
    BodyOperator op(bodies_);
    const bool implicit = implicit_exchange_usable();
    HitArrays h = hits();
    if (near && push_in_exchange_) h.bias = bias_.data();
    const CoupleStats cs = coupler_->apply(h, f, surfaces_, implicit ? &op : nullptr);
    if (push_in_exchange_) return_late_pushes(f);
    push_in_exchange_ = false;
    stats_.contacts += cs.contacts;
    stats_.joint_rounds += cs.rounds;
    stats_.joint_iterations += cs.iterations;
    // The bodies took their share as a velocity change, not through the impulse array.
    if (implicit)
      for (std::size_t b = 0; b < stats_.body_impulse.size() && b < cs.body_impulse.size(); ++b)
        stats_.body_impulse[b] += cs.body_impulse[b];
  }

  // Near-surface density: a particle its ray did not stop that ends the step within a
  // particle radius in front of its closest face (at the face's new position) joins the
  // exchange as a contact of that face. The fluid's pressure saw the face at its old velocity;
  // the body's step then moved it with the pressure's impulse, and a light body moves far: the
  // contact solves the mismatch with the body's inertia, as a collision, rather than leaving
  // it to the next step's pressure (the added-mass instability of a staggered coupling).
  //
  // A particle whose normal push the exchange took (near_push_) becomes a contact held at the
  // separation speed the fluid's solve gave it from the face as the fluid saw it, with its
  // push taken back first: against an immovable face it gets exactly its push again; against a
  // light one, the face gives way by what the body's step operator says. One whose ray hit
  // some face, or that ended behind its face, keeps its push (returned late, for the next
  // step).
  void add_near_contacts(const FluidArrays& f) {
    const BodyArrays a = bodies_->arrays();
    int* face = face_.data();
    Real *t = t_.data(), *u = u_.data(), *v = v_.data(), *bias = bias_.data();
    Real* push = near_push_.data();
    const int* nf = near_face_.data();
    const Real *nu = near_u_.data(), *nv = near_v_.data();
    const Vec3 *n0 = near_n_.data(), *vs0 = near_vel_.data();
    const Vec3* px = f.x;
    Vec3* pv = f.v;
    const Vec3* nx = a.x;
    const Tri* tris = a.surface;
    const Real reach = Real(0.25) * set_.support;  // the particle radius
    const bool pushes = push_in_exchange_;
    parallel_for(ex_, f.n, [=] SPHFEM_LAMBDA(int i) {
      if (pushes) bias[i] = Real(NAN);
      if (face[i] >= 0 || nf[i] < 0) return;
      const Tri tr = tris[nf[i]];
      const Vec3 p0 = nx[tr.v[0]], p1 = nx[tr.v[1]], p2 = nx[tr.v[2]];
      const Vec3 c = p0 * (Real(1) - nu[i] - nv[i]) + p1 * nu[i] + p2 * nv[i];
      const Real d = dot(px[i] - c, couple::face_normal(p0, p1, p2));
      const bool pushed = pushes && push[i] > Real(0);
      if (!(d > Real(0) && (pushed || d < reach))) return;
      face[i] = nf[i];
      t[i] = Real(0);
      u[i] = nu[i];
      v[i] = nv[i];
      if (!pushed) return;
      bias[i] = dot(pv[i] - vs0[i], n0[i]);
      pv[i] -= n0[i] * push[i];
      push[i] = Real(0);
    });
    exec_sync(ex_);
  }

  // The pushes add_near_contacts could not hand to the exchange, to the faces' nodes for the
  // next step (as return_surface_pressure does when the exchange takes none).
  void return_late_pushes(const FluidArrays& f) { return_near_impulse(f, Real(0), Real(1)); }

  // To the nodes of each particle's closest face (near_face_), the opposite of the particle's
  // momentum change m (a_dv dv_i + a_push push_i n_i), by the barycentric weights of the
  // closest point, summed node by node in particle order (core/node_sums.h). dv_i is the
  // near-surface pressure's change (near_dv_), push_i n_i its normal push kept for the
  // exchange (near_push_, never negative).
  void return_near_impulse(const FluidArrays& f, Real a_dv, Real a_push) {
    if (body_tris_ == 0) return;
    const BodyArrays a = bodies_->arrays();
    const int* face = near_face_.data();
    const Real *u = near_u_.data(), *v = near_v_.data(), *push = near_push_.data();
    const Vec3 *dv = near_dv_.data(), *nrm = near_n_.data();
    const Tri* tris = a.surface;
    const Real m = f.mass;
    node_sums_.add(
        ex_, 3 * f.n, a.nodes,
        [=] SPHFEM_LAMBDA(int k, int& node, Vec3& value) {
          const int i = k / 3, c = k % 3;
          if (face[i] < 0) return;
          const Vec3 d = dv[i] * a_dv + nrm[i] * (a_push * push[i]);
          if (d.x == Real(0) && d.y == Real(0) && d.z == Real(0)) return;
          const Real w = c == 0 ? Real(1) - u[i] - v[i] : c == 1 ? u[i] : v[i];
          node = tris[face[i]].v[c];
          value = d * (-m * w);
        },
        a.impulse);
  }

  // Baseline: no ray and no drift limit; the bodies' BVH follows them for the leak check.
  DriftLimits baseline_cast(const FluidArrays& f) {
    if (body_tris_ == 0) return DriftLimits();
    grow(f.n);
    refit_bodies();
    copy(x_pre_.data(), f.x, f.n);
    exec_sync(ex_);
    return DriftLimits();
  }

  void refit_bodies() {
    const BodyArrays a = bodies_->arrays();
    body_bvh_.refit(ex_, x_old_.data(), a.x);
    if (body_bvh_.quality(ex_) > set_.rebuild_quality) {
      body_bvh_.rebuild(ex_, a.x);
      body_bvh_.refit(ex_, x_old_.data(), a.x);
      ++stats_.rebuilds;
    }
  }

  // The near-surface pressure the fluid felt this step (SurfaceProximity::dv), returned to the
  // closest face's nodes by the barycentric weights of the closest point, summed node by node
  // in particle order (core/node_sums.h).
  void return_surface_pressure(const FluidArrays& f) {
    const int* face = near_face_.data();
    const Vec3* dv = near_dv_.data();
    const Vec3* nrm = near_n_.data();
    const Real* dist = near_dist_.data();
    Real* push = near_push_.data();
    const bool keep = push_in_exchange_;
    // With the implicit exchange the normal push of a particle in front of its face waits for
    // the exchange, which shares it between the particle and the body by the body's response.
    parallel_for(ex_, f.n, [=] SPHFEM_LAMBDA(int i) {
      const Real p = face[i] >= 0 && keep && dist[i] > Real(0) ? dot(dv[i], nrm[i]) : Real(0);
      push[i] = p > Real(0) ? p : Real(0);
    });
    stats_.near_surface +=
        long(reduce_sum(ex_, f.n,
                        [=] SPHFEM_LAMBDA(int i) -> double { return face[i] >= 0 ? 1.0 : 0.0; }) +
             0.5);
    return_near_impulse(f, Real(1), Real(-1));
  }

  // What the fluid gave each body since its last step (rays, samples and near-surface
  // pressure alike), read from the nodes' impulse array before the step consumes it.
  void collect_body_impulse() {
    const BodyArrays a = bodies_->arrays();
    const std::vector<int>& off = bodies_->model().node_offset;
    const Vec3* J = a.impulse;
    for (std::size_t b = 0; b + 1 < off.size() && b < stats_.body_impulse.size(); ++b) {
      const int first = off[b], count = off[b + 1] - off[b];
      Vec3d sum;
      sum.x = reduce_sum(ex_, count, [=] SPHFEM_LAMBDA(int k) -> double { return J[first + k].x; });
      sum.y = reduce_sum(ex_, count, [=] SPHFEM_LAMBDA(int k) -> double { return J[first + k].y; });
      sum.z = reduce_sum(ex_, count, [=] SPHFEM_LAMBDA(int k) -> double { return J[first + k].z; });
      stats_.body_impulse[b] += sum;
    }
  }

  using Clock = std::chrono::steady_clock;
  static double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  }

  template <class T>
  static void grow_buffer(Buffer<T>& b, int n) {
    if (b.size() < std::size_t(n)) b.resize(std::size_t(n) + std::size_t(n) / 4);
  }

  void grow(int n) {
    for (Buffer<int>* b : {&face_, &tank_face_, &crossing_side_}) grow_buffer(*b, n);
    for (Buffer<Real>* b : {&t_, &u_, &v_, &len_, &tank_t_, &tank_u_, &tank_v_, &tank_len_})
      grow_buffer(*b, n);
    for (Buffer<Real>* b : {&near_dist_, &near_u_, &near_v_, &near_slip_, &near_push_, &bias_})
      grow_buffer(*b, n);
    grow_buffer(near_face_, n);
    for (Buffer<Vec3>* b : {&x_pre_, &rel_, &near_n_, &near_vel_, &near_dv_}) grow_buffer(*b, n);
    if (solid_tris_ > 0) {
      for (Buffer<int>* b : {&solid_face_, &solid_side_}) grow_buffer(*b, n);
      for (Buffer<Real>* b : {&solid_dist_, &solid_u_, &solid_v_}) grow_buffer(*b, n);
      grow_buffer(solid_point_, n);
    }
  }

  void copy(Vec3* dst, const Vec3* src, int n) {
    parallel_for(ex_, n, [=] SPHFEM_LAMBDA(int i) { dst[i] = src[i]; });
  }

  // The static set: the tank's inner faces (8 corners, 2 triangles a face, no lid when the
  // top is open) when they are ray-cast, then the obstacles' triangles.
  void build_statics() {
    std::vector<Vec3> c;
    std::vector<Tri> tris;
    static_offset_ = {0};
    static_coeffs_.clear();
    if (set_.tank) {
      const Vec3 lo = set_.tank_lo, hi = set_.tank_hi;
      for (int k = 0; k < 8; ++k)
        c.push_back(Vec3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z));
      // Quads by corner index (bit 0 = x, bit 1 = y, bit 2 = z).
      const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                               {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
      for (int q = 0; q < 6; ++q) {
        if (set_.open_top && q == 3) continue;  // y = hi
        const int* k = quads[q];
        tris.push_back(Tri{{k[0], k[1], k[2]}});
        tris.push_back(Tri{{k[0], k[2], k[3]}});
      }
      static_offset_.push_back(int(tris.size()));
      static_coeffs_.push_back(set_.wall);
    }
    const int base = int(c.size()), first = int(tris.size());
    obstacle_base_ = base;
    c.insert(c.end(), set_.obstacle_x.begin(), set_.obstacle_x.end());
    for (Tri t : set_.obstacle_tris) {
      for (int& v : t.v) v += base;
      tris.push_back(t);
    }
    for (std::size_t k = 1; k < set_.obstacle_offset.size(); ++k) {
      static_offset_.push_back(first + set_.obstacle_offset[k]);
      static_coeffs_.push_back(set_.obstacle_coeffs[k - 1]);
    }
    static_nodes_ = int(c.size());
    tank_x_ = Buffer<Vec3>(Exec::kSpace, c.size());
    tank_x_.upload(c.data(), c.size());
    tank_tri_ = Buffer<Tri>(Exec::kSpace, tris.size());
    tank_tri_.upload(tris.data(), tris.size());
    tank_tris_ = int(tris.size());
    tank_bvh_.build(ex_, tank_x_.data(), tank_tri_.data(), tank_tris_);
    tank_bvh_.refit(ex_, tank_x_.data(), tank_x_.data());
    // The closed obstacles' faces, for the near-surface density.
    std::vector<Tri> solid;
    std::vector<Real> slip;
    for (std::size_t k = 0; set_.near_surface && k + 1 < set_.obstacle_offset.size(); ++k) {
      if (k >= set_.obstacle_closed.size() || !set_.obstacle_closed[k]) continue;
      for (int t = set_.obstacle_offset[k]; t < set_.obstacle_offset[k + 1]; ++t) {
        solid.push_back(tris[std::size_t(first + t)]);
        slip.push_back(set_.obstacle_coeffs[k].slip);
      }
    }
    solid_tris_ = int(solid.size());
    if (solid_tris_ == 0) return;
    solid_tri_ = Buffer<Tri>(Exec::kSpace, solid.size());
    solid_tri_.upload(solid.data(), solid.size());
    solid_slip_ = Buffer<Real>(Exec::kSpace, slip.size());
    solid_slip_.upload(slip.data(), slip.size());
    solid_bvh_.build(ex_, tank_x_.data(), solid_tri_.data(), solid_tris_);
    solid_bvh_.refit(ex_, tank_x_.data(), tank_x_.data());
    for (Buffer<int>* b : {&solid_face_, &solid_side_}) *b = Buffer<int>(Exec::kSpace);
    for (Buffer<Real>* b : {&solid_dist_, &solid_u_, &solid_v_}) *b = Buffer<Real>(Exec::kSpace);
    solid_point_ = Buffer<Vec3>(Exec::kSpace);
  }

  void fill_no_hit(int n) {
    int* face = face_.data();
    parallel_for(ex_, n, [=] SPHFEM_LAMBDA(int i) { face[i] = -1; });
  }

  // The nearest of a body hit and a tank hit, compared as fractions of each cast's length
  // (the two casts measure relative to different surfaces). Tank faces follow the bodies'.
  void merge_tank_hits(int n) {
    int* face = face_.data();
    Real *t = t_.data(), *u = u_.data(), *v = v_.data(), *len = len_.data();
    const int* tf = tank_face_.data();
    const Real *tt = tank_t_.data(), *tu = tank_u_.data(), *tv = tank_v_.data();
    const Real* tl = tank_len_.data();
    const int offset = body_tris_;
    parallel_for(ex_, n, [=] SPHFEM_LAMBDA(int i) {
      if (tf[i] < 0) return;
      const Real lt = tl[i] > Real(0) ? tl[i] : Real(1);
      const Real lb = len[i] > Real(0) ? len[i] : Real(1);
      if (face[i] >= 0 && t[i] * lt <= tt[i] * lb) return;  // t/lb <= tt/lt
      face[i] = tf[i] + offset;
      t[i] = tt[i];
      u[i] = tu[i];
      v[i] = tv[i];
      len[i] = tl[i];
    });
  }

  // coupling.implicit_exchange asks for it; it needs body faces and a body step to answer.
  bool implicit_exchange_usable() const {
    return set_.implicit_exchange && body_tris_ > 0 && bodies_->last_dt() > 0;
  }

  HitArrays hits() const {
    HitArrays h;
    h.space = Exec::kSpace;
    h.face = face_.data();
    h.t = t_.data();
    h.u = u_.data();
    h.v = v_.data();
    return h;
  }

  std::vector<CoupleSurface> surfaces() {
    std::vector<CoupleSurface> s;
    if (body_tris_ > 0) s.push_back(body_surface(bodies_->arrays(), bodies_->model(), set_.body));
    if (tank_tris_ > 0) {
      CoupleSurface st = static_surface(Exec::kSpace, static_nodes_, tank_x_.data(), tank_tris_,
                                        tank_tri_.data(), set_.wall);
      st.tri_offset = static_offset_;
      st.coeffs = static_coeffs_;
      if (statics_move_) st.v = static_vel_.data();
      s.push_back(st);
    }
    return s;
  }

  // The one ray per particle respects only its nearest face, and moves that face with one
  // point's displacement: a particle stopped by the tank, or carried with one face, can still
  // be crossed by another face moving differently (a cloth edge beside a wall, a concave
  // corner), or by a face that turns within the step. So each particle's actual path over the
  // step is tested again, exactly, against every face of a set (the bodies', or the moving
  // obstacles') moving linearly from its old to its new position (collide::moving_contact).
  // A particle that met a face from in front is put a skin in front of that face's new
  // position and tested again; one leaving a body from behind its faces (let in by an inverted
  // element) is let go. A two-sided set (open obstacle surfaces) puts the particle back on the
  // side it came from. The first test is the leak check; what still meets a face after the
  // last pass is counted in `crossed`. The baseline (passes = 1) only counts.
  long resolve_crossings(const FluidArrays& f, int kPasses, const SurfaceBvh<Exec>& bvh,
                         const Vec3* x_old, const Vec3* x_new, const Tri* tris, bool two_sided) {
    const int n = f.n;
    Vec3* x = f.x;
    const Vec3* pre = x_pre_.data();
    const Real skin = set_.skin;
    // Rounding of the contact test; far below the skin the fix keeps.
    const Real tol = collide::rmax(Real(0.01) * skin, Real(1e-7));
    int* face = tank_face_.data();  // the coupler is done with the tank's hit buffers
    Real *tau = tank_t_.data(), *hu = tank_u_.data(), *hv = tank_v_.data();
    int* side = two_sided ? crossing_side_.data() : nullptr;
    long crossed = 0;
    for (int pass = 0; pass < kPasses; ++pass) {
      const auto t0 = Clock::now();
      // One-sided: front contacts only (entries), so the fix always puts the particle in front.
      cast_contacts(ex_, bvh, x_old, x_new, n, pre, x, tol, ContactHits{face, tau, hu, hv, side},
                    /*front_only=*/!two_sided);
      const double c = reduce_sum(
          ex_, n, [=] SPHFEM_LAMBDA(int i) -> double { return face[i] >= 0 ? 1.0 : 0.0; });
      crossed = long(c + 0.5);
      if (pass == 0) stats_.ms_leak_check += ms_since(t0);
      if (crossed == 0 || pass == kPasses - 1) break;
      const Vec3* nx = x_new;
      // A particle that meets a face again after being put a skin in front of one sits where
      // two faces have closed to less than a skin (a fold, a pocket): each pass puts it at half
      // the last distance, so it comes to fit the gap instead of going back and forth.
      const Real put = skin / Real(1 << pass);
      parallel_for(ex_, n, [=] SPHFEM_LAMBDA(int i) {
        if (face[i] < 0) return;
        const Tri tr = tris[face[i]];
        const Vec3 p0 = nx[tr.v[0]], p1 = nx[tr.v[1]], p2 = nx[tr.v[2]];
        const Vec3 c = p0 * (Real(1) - hu[i] - hv[i]) + p1 * hu[i] + p2 * hv[i];
        const Real away = side && side[i] < 0 ? -put : put;
        x[i] = c + couple::face_normal(p0, p1, p2) * away;
      });
      exec_sync(ex_);
      stats_.corrected += crossed;
    }
    return crossed;
  }

  RayCouplingSettings set_;
  BodySolver* bodies_;
  std::unique_ptr<Coupler> coupler_;
  Exec ex_;
  SurfaceBvh<Exec> body_bvh_, tank_bvh_;
  int body_tris_ = 0, tank_tris_ = 0;  // tank_*: the static set, the tank's and obstacles'
  int static_nodes_ = 0;
  std::vector<int> static_offset_;
  std::vector<ContactCoeffs> static_coeffs_;
  Buffer<Vec3> x_old_, tank_x_, x_pre_, rel_;
  // Obstacles on a path: the static set's vertices at the start of the step and their
  // velocities over it (move_obstacles); obstacle_base_: the tank's corners before them.
  Buffer<Vec3> tank_x_old_, static_vel_;
  bool statics_move_ = false;
  int obstacle_base_ = 0;
  Buffer<int> crossing_side_;
  // The closed obstacles' faces (indices into tank_x_), for the near-surface density, and
  // each particle's closest one.
  SurfaceBvh<Exec> solid_bvh_;
  int solid_tris_ = 0;
  Buffer<Tri> solid_tri_;
  Buffer<Real> solid_slip_;
  Buffer<int> solid_face_, solid_side_;
  Buffer<Real> solid_dist_, solid_u_, solid_v_;
  Buffer<Vec3> solid_point_;
  Buffer<Tri> tank_tri_;
  Buffer<int> face_, tank_face_;
  Buffer<Real> t_, u_, v_, len_, tank_t_, tank_u_, tank_v_, tank_len_;
  // Near-surface density: each particle's closest body face this step.
  Buffer<int> near_face_;
  Buffer<Real> near_dist_, near_u_, near_v_, near_slip_;
  // With the implicit exchange: the normal push (m/s) the near-surface pressure gave each
  // particle, left to the exchange; and the exchange's per-particle bias (HitArrays::bias).
  Buffer<Real> near_push_, bias_;
  bool push_in_exchange_ = false;

  Buffer<Real> face_slip_;  // per body face, its body's slip coefficient
  Buffer<Vec3> near_n_, near_vel_, near_dv_;
  int near_n_active_ = 0;  // particles proximity() found surfaces for, this step
  int near_n_step_ = 0;    // the same, kept until the exchange
  NodeSums<Exec> node_sums_;
  std::vector<CoupleSurface> surfaces_;
  RayCouplingStats stats_;
};

}  // namespace sphfem
