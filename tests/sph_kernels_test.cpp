// Kernels: normalised, compact, gradient antisymmetric and equal to the finite difference.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sphfem/sph/kernels.h"

using namespace sphfem;

namespace {

// Integral of W over space by a fine lattice (midpoint rule).
double integrate(const Kernel& k, double h) {
  const int n = 80;
  const double dx = 2.0 * h / n;
  double sum = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int l = 0; l < n; ++l) {
        const double x = -h + (i + 0.5) * dx, y = -h + (j + 0.5) * dx, z = -h + (l + 0.5) * dx;
        sum += k.W(Real(std::sqrt(x * x + y * y + z * z)));
      }
  return sum * dx * dx * dx;
}

class SphKernel : public ::testing::TestWithParam<int> {};

TEST_P(SphKernel, IsNormalised) {
  const double h = 0.1;
  const Kernel k(GetParam(), Real(h));
  EXPECT_NEAR(integrate(k, h), 1.0, 2e-3);
}

TEST_P(SphKernel, VanishesOutsideSupport) {
  const Kernel k(GetParam(), Real(0.1));
  EXPECT_EQ(k.W(Real(0.1)), Real(0));
  EXPECT_EQ(k.W(Real(0.25)), Real(0));
  EXPECT_GT(k.W(Real(0.0999)), Real(0));
  EXPECT_GT(k.W(Real(0)), k.W(Real(0.05)));
}

TEST_P(SphKernel, GradientIsAntisymmetricAndMatchesFiniteDifference) {
  const double h = 0.1;
  const Kernel k(GetParam(), Real(h));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.07, 0.07);
  for (int t = 0; t < 200; ++t) {
    const Vec3d r(u(rng), u(rng), u(rng));
    const double rr = norm(r);
    if (rr < 1e-3 || rr > 0.099) continue;
    const Vec3 g = k.grad(Vec3(r), Real(rr));
    const Vec3 gm = k.grad(Vec3(-r), Real(rr));
    EXPECT_NEAR(g.x, -gm.x, 1e-6 * std::fabs(g.x) + 1e-9);
    EXPECT_NEAR(g.y, -gm.y, 1e-6 * std::fabs(g.y) + 1e-9);
    EXPECT_NEAR(g.z, -gm.z, 1e-6 * std::fabs(g.z) + 1e-9);
    const double e = 1e-5;
    for (int c = 0; c < 3; ++c) {
      Vec3d rp = r, rm = r;
      rp[c] += e;
      rm[c] -= e;
      const double fd = (double(k.W(Real(norm(rp)))) - double(k.W(Real(norm(rm))))) / (2 * e);
      const double scale = double(k.W(Real(0))) / h;
      EXPECT_NEAR(double(g[c]), fd, 2e-3 * scale) << "component " << c << " at r=" << rr;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Kernels, SphKernel, ::testing::Values(0, 1),
                         [](const auto& info) { return info.param == 0 ? "CubicSpline" : "WendlandC2"; });

}  // namespace
