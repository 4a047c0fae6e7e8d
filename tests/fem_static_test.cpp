// Static answers of the co-rotated FEM against beam and bar theory. Statics come from the
// dynamic solver itself: an implicit Euler step from rest with dt far above the lowest
// period is a Newton step towards equilibrium, regularised by the small mass term M / dt^2,
// and zeroing the velocities between steps (kinetic damping) leaves only the remaining
// static residual for the next step. (dt must not be so large that M / dt^2 stops
// regularising: in single precision CG, a relative residual of 1e-6 then no longer resolves
// the softest bending mode.)
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sphfem/fem/solver.h"

using namespace sphfem;

namespace {

// Newton iterations through large implicit steps until the displacement stops changing.
void solve_static(BodySolver& s, double dt, int max_steps, double tol) {
  BodySnapshot a, b;
  s.snapshot(a);
  const std::vector<Vec3> zero(s.node_count());
  for (int k = 0; k < max_steps; ++k) {
    s.step(dt);
    s.set_velocities(zero);
    s.snapshot(b);
    double change = 0, size = 0;
    for (int i = 0; i < b.n; ++i) {
      change = std::max(change, double(norm(b.x[i] - a.x[i])));
      size = std::max(size, double(norm(b.x[i] - Vec3(s.model().x0[i]))));
    }
    if (change <= tol * size) return;
    a = b;
  }
}

FemSettings static_settings() {
  FemSettings s;
  s.cg_tolerance = 1e-6;
  s.cg_max_iterations = 20000;
  s.rotation_iterations = 10;
  return s;
}

}  // namespace

TEST(FemStatic, CantileverTipDeflectionMatchesTimoshenko) {
  // Square beam L = 0.5 m, h = b = 0.1 m (L/h = 5), clamped at x = 0 (every node of that
  // face pinned), under its own weight. E = 1e8 Pa, rho = 1000 kg/m^3: the tip deflects
  // 0.2 % of L, well inside linear beam theory; at L/h = 5 the Timoshenko shear term is 3.2 %
  // of the bending term. nu = 0, so clamping the whole root face matches the beam's clamp (no
  // restrained lateral contraction). Cubic cells, n = 4, 8, 12 through the thickness (1.9k,
  // 15k, 52k tets): linear tetrahedra are stiff in bending (shear locking) and measure
  // -17.4 %, -5.1 %, -2.4 % against Euler-Bernoulli plus the shear term. Steps of dt = 1 s:
  // the first bending mode has omega_1 dt ~ 120.
  const double L = 0.5, h = 0.1, E = 1e8, nu = 0.0, rho = 1000.0, g = 9.81;
  const double q = rho * g * h * h, I = h * h * h * h / 12.0, A = h * h;
  // Shear coefficient of a rectangular section (Cowper 1966).
  const double G = E / (2 * (1 + nu)), kappa = 10 * (1 + nu) / (12 + 11 * nu);
  const double bending = q * L * L * L * L / (8 * E * I);
  const double shear = q * L * L / (2 * kappa * G * A);
  const double exact = bending + shear;
  double last = 1.0;
  for (int n : {4, 8, 12}) {
    const auto t0 = std::chrono::steady_clock::now();
    const TetMesh mesh =
        make_box(Vec3d(0, -0.5 * h, -0.5 * h), Vec3d(L, 0.5 * h, 0.5 * h), 5 * n, n, n);
    Material mat;
    mat.density = rho, mat.young = E, mat.poisson = nu;
    const auto pinned = pin_nodes(mesh, [](const Vec3d& x) { return x.x < 1e-9; });
    FemSettings set = static_settings();
    set.gravity = Vec3d(0, -g, 0);
    auto solver =
        make_body_solver(compile_bodies({compile_body(mesh, mat, pinned)}, set), Backend::Cpu);
    solve_static(*solver, 1.0, 10, 1e-4);
    BodySnapshot s;
    solver->snapshot(s);
    double tip = 0;
    int count = 0;
    for (int i = 0; i < s.n; ++i)
      if (mesh.x[i].x > L - 1e-9) tip += mesh.x[i].y - s.x[i].y, ++count;
    tip /= count;
    const double err = (tip - exact) / exact;
    std::printf(
        "[ measured ] cantilever n=%d (%zu tets): tip %.5g m, theory %.5g m, error %.2f %%"
        " (%.1f s, %ld CG iterations)\n",
        n, mesh.tets.size(), tip, exact, 100 * err,
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
        solver->profile().cg_iterations);
    EXPECT_LT(std::fabs(err), last) << n;
    last = std::fabs(err);
  }
  EXPECT_LT(last, 0.05);
}

TEST(FemStatic, HangingBarStretchesByFLOverEA) {
  // Bar 0.1 x 1 x 0.1 m hanging from its pinned top face, a dead load F pulling its bottom
  // face down, no gravity. With nu = 0 the pinned top does not restrain lateral contraction,
  // the stress is uniform and the elongation is F L / (E A) = 1 % of L. Steps of 0.05 s: a
  // larger quasi-static step lets the bar's lateral modes diverge, because the warped
  // stiffness R K_e R^T lacks the stabilising stiffness of the tension (solver.h).
  const double L = 1.0, w = 0.1, E = 1e6, A = w * w, F = 0.01 * E * A;
  const TetMesh mesh = make_box(Vec3d(0, -L, 0), Vec3d(w, 0, w), 3, 30, 3);
  Material mat;
  mat.young = E, mat.poisson = 0.0;
  const auto pinned = pin_nodes(mesh, [](const Vec3d& x) { return x.y > -1e-9; });
  FemSettings set = static_settings();
  set.gravity = Vec3d();
  const BodiesModel model = compile_bodies({compile_body(mesh, mat, pinned)}, set);
  // Traction F / A on the bottom face: each boundary triangle there gives a third of its
  // share to each of its nodes (consistent nodal loads of a uniform traction).
  std::vector<Vec3> load(mesh.x.size());
  for (const Tri& t : model.surface) {
    const Vec3d a = mesh.x[t.v[0]], b = mesh.x[t.v[1]], c = mesh.x[t.v[2]];
    if (a.y > -L + 1e-9 || b.y > -L + 1e-9 || c.y > -L + 1e-9) continue;
    const double area = 0.5 * norm(cross(b - a, c - a));
    for (int k = 0; k < 3; ++k) load[t.v[k]] += Vec3(0, Real(-F * area / A / 3), 0);
  }
  auto solver = make_body_solver(model, Backend::Cpu);
  solver->set_node_forces(load);
  solve_static(*solver, 0.05, 10, 1e-4);
  BodySnapshot s;
  solver->snapshot(s);
  double stretch = 0;
  int count = 0;
  for (int i = 0; i < s.n; ++i)
    if (mesh.x[i].y < -L + 1e-9) stretch += mesh.x[i].y - s.x[i].y, ++count;
  stretch /= count;
  const double exact = F * L / (E * A);
  std::printf("[ measured ] hanging bar: elongation %.6g m, F L/(E A) %.6g m, error %.4f %%\n",
              stretch, exact, 100 * (stretch - exact) / exact);
  EXPECT_NEAR(stretch, exact, 0.01 * exact);
}
