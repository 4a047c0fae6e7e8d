// Co-rotated elastic forces (paper eq. 5) and the rotation extraction behind them
// (Mueller et al. 2016): rigid motions produce no force, forces turn with the body
// (f(Q x + c) = Q f(x)), and the extracted rotation is a proper rotation for any deformation
// gradient, including flat and inverted ones.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "fem/polar.h"
#include "sphfem/fem/solver.h"

using namespace sphfem;

namespace {

constexpr double kPi = 3.14159265358979323846;

Mat3d rotation(Vec3d axis, double angle) {
  return Q4<double>::from_rotation_vector(axis * (angle / norm(axis))).matrix();
}

double max_norm(const std::vector<Vec3>& f) {
  double m = 0;
  for (const Vec3& v : f) m = std::max(m, double(norm(v)));
  return m;
}

double orthonormality_error(const Mat3d& R) {
  const Mat3d I = transpose(R) * R;
  double e = std::fabs(det(R) - 1.0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) e = std::max(e, std::fabs(I.m[i][j] - (i == j ? 1.0 : 0.0)));
  return e;
}

struct Fixture {
  TetMesh mesh = make_sphere(Vec3d(0, 0, 0), 0.1, 4);
  Material mat;
  std::unique_ptr<BodySolver> solver;
  Fixture() {
    mat.young = 1e5;
    mat.poisson = 0.35;
    solver =
        make_body_solver(compile_bodies({compile_body(mesh, mat)}, FemSettings()), Backend::Cpu);
  }
  // Force scale of a unit strain on one element face: E * (cell size)^2.
  double force_scale() const { return mat.young * 0.05 * 0.05; }
  std::vector<Vec3> forces_at(const std::vector<Vec3d>& x) {
    std::vector<Vec3> xs(x.size()), f;
    for (std::size_t i = 0; i < x.size(); ++i) xs[i] = Vec3(x[i]);
    solver->set_positions(xs);
    solver->elastic_forces(f);
    return f;
  }
};

// A smooth, large, non-rigid deformation of the rest shape: stretch, shear and twist.
Vec3d deform(const Vec3d& X) {
  const double t = 3.0 * X.y;  // up to 0.3 rad of twist about y
  const Vec3d s(1.25 * X.x + 0.3 * X.y, 0.8 * X.y + 0.2 * X.x * X.x / 0.1, 1.1 * X.z);
  return Vec3d(std::cos(t) * s.x - std::sin(t) * s.z, s.y, std::sin(t) * s.x + std::cos(t) * s.z);
}

}  // namespace

TEST(FemElastic, RestShapeAndRigidMotionsAreForceFree) {
  Fixture fx;
  std::vector<Vec3d> x = fx.mesh.x;
  EXPECT_LT(max_norm(fx.forces_at(x)), 1e-5 * fx.force_scale());
  // Any rotation, up to a half turn, plus a translation.
  for (double angle : {0.3, 1.4, 2.2, 2.6, 3.1}) {
    const Mat3d Q = rotation(Vec3d(1, 2, -0.5), angle);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = Q * fx.mesh.x[i] + Vec3d(0.4, -1.0, 2.0);
    EXPECT_LT(max_norm(fx.forces_at(x)), 1e-4 * fx.force_scale()) << "angle " << angle;
  }
}

TEST(FemElastic, ForcesRotateWithTheBody) {
  Fixture fx;
  std::vector<Vec3d> x(fx.mesh.x.size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = deform(fx.mesh.x[i]);
  const std::vector<Vec3> f = fx.forces_at(x);
  const double fmax = max_norm(f);
  EXPECT_GT(fmax, 0.05 * fx.force_scale());  // the deformation is far from rigid
  // Net force and torque of internal forces vanish.
  Vec3d net, torque;
  for (std::size_t i = 0; i < f.size(); ++i) {
    net += Vec3d(f[i]);
    torque += cross(x[i], Vec3d(f[i]));
  }
  EXPECT_LT(norm(net), 1e-5 * fmax * f.size());
  EXPECT_LT(norm(torque), 1e-4 * fmax * 0.1 * f.size());

  for (double angle : {0.7, 2.0, 3.0}) {
    const Mat3d Q = rotation(Vec3d(-0.3, 1, 0.8), angle);
    std::vector<Vec3d> y(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) y[i] = Q * x[i] + Vec3d(-0.2, 0.5, 0.1);
    const std::vector<Vec3> g = fx.forces_at(y);
    double err = 0;
    for (std::size_t i = 0; i < f.size(); ++i)
      err = std::max(err, norm(Vec3d(g[i]) - Q * Vec3d(f[i])));
    EXPECT_LT(err, 1e-4 * fmax) << "angle " << angle;
  }
}

TEST(FemElastic, RotationExtractionIsProperForAnyDeformation) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Mat3d Q = rotation(Vec3d(u(rng), u(rng), u(rng)), 0.9 * kPi * std::fabs(u(rng)));
    // Symmetric positive definite stretch S = B^T B + 0.2 I.
    Mat3d B;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) B.m[i][j] = u(rng);
    Mat3d S = transpose(B) * B;
    for (int i = 0; i < 3; ++i) S.m[i][i] += 0.2;
    const Mat3d F = Q * S;
    // From the identity: converges to the polar rotation Q.
    const Mat3d R = fem::extract_rotation(F, Q4<double>::identity(), 200).matrix();
    double err = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) err = std::max(err, std::fabs(R.m[i][j] - Q.m[i][j]));
    EXPECT_LT(err, 1e-8) << "trial " << trial;
    // Flat (rank 2) and inverted (det < 0) gradients still give proper rotations.
    Mat3d flat = F, inv = F;
    for (int i = 0; i < 3; ++i) flat.m[i][2] = 0.0, inv.m[i][2] = -F.m[i][2];
    for (const Mat3d& A : {flat, inv}) {
      const Mat3d Ra = fem::extract_rotation(A, Q4<double>::identity(), 20).matrix();
      EXPECT_LT(orthonormality_error(Ra), 1e-12);
    }
  }
}

TEST(FemElastic, CubeRotationsAreDistinctUnitQuaternions) {
  for (int s = 0; s < 24; ++s) {
    const Q4<double> a = fem::cube_rotation<double>(s);
    EXPECT_NEAR(a.w * a.w + a.x * a.x + a.y * a.y + a.z * a.z, 1.0, 1e-15);
    for (int t = 0; t < s; ++t) {
      const Q4<double> b = fem::cube_rotation<double>(t);
      EXPECT_LT(std::fabs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z), 0.99) << s << " " << t;
    }
  }
}

TEST(FemElastic, WarmStartedRotationConvergesInFewIterations) {
  // One step of a spinning, straining element: last step's rotation is 0.05 rad away.
  Mat3d S = Mat3d::identity();
  S.m[0][0] = 1.1, S.m[0][1] = S.m[1][0] = 0.05, S.m[2][2] = 0.9;
  const Q4<double> q_prev = Q4<double>::from_rotation_vector(Vec3d(0.3, -0.2, 0.5));
  const Mat3d Q = Q4<double>::from_rotation_vector(Vec3d(0.33, -0.21, 0.53)).matrix();
  const Mat3d R = fem::extract_rotation(Q * S, q_prev, 4).matrix();
  double err = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) err = std::max(err, std::fabs(R.m[i][j] - Q.m[i][j]));
  EXPECT_LT(err, 2e-3);  // 0.05 rad shrinks about threefold per iteration
}
