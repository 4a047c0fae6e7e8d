// The hydrostatic check shared by the SPH column tests: snapshots of a settled column, the
// particles within a square prism about a vertical line binned by height, their mean pressure
// compared with rho g (H - y), H the free surface (the top particle centres, averaged, plus a
// radius).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "sphfem/sph/solver.h"

namespace sphfem::test {

class PressureProfile {
 public:
  // Bins of height `range` / nbins from y = 0; the line is the particles within half_width of
  // (cx, cz) in x and z.
  PressureProfile(int nbins, double range, double cx, double cz, double half_width)
      : nbins_(nbins),
        range_(range),
        cx_(cx),
        cz_(cz),
        hw_(half_width),
        psum_(nbins, 0.0),
        ysum_(nbins, 0.0),
        cnt_(nbins, 0) {}

  void add(const FluidSnapshot& s) {
    double ymax = 0;
    for (int i = 0; i < s.n; ++i) {
      const Vec3 x = s.x[i];
      ymax = std::max(ymax, double(x.y));
      if (std::fabs(x.x - cx_) > hw_ || std::fabs(x.z - cz_) > hw_) continue;
      const int b = std::max(0, std::min(nbins_ - 1, int(x.y / range_ * nbins_)));
      psum_[b] += s.p[i];
      ysum_[b] += x.y;
      ++cnt_[b];
    }
    top_ += ymax;
    ++samples_;
  }

  double surface(double radius) const { return top_ / samples_ + radius; }

  struct Error {
    double l2;      // over the filled bins, relative to the exact profile
    double bottom;  // mean pressure of the lowest filled bin over the exact one, minus 1
  };
  Error against(double height, double rho = 1000.0, double g = 9.81) const {
    Error e{0, 0};
    double num = 0, den = 0;
    bool bottom = true;
    for (int b = 0; b < nbins_; ++b) {
      if (!cnt_[b]) continue;
      const double y = ysum_[b] / cnt_[b], p = psum_[b] / cnt_[b];
      const double exact = rho * g * (height - y);
      if (bottom) e.bottom = p / exact - 1, bottom = false;
      num += (p - exact) * (p - exact);
      den += exact * exact;
      if (std::getenv("SPHFEM_VERBOSE")) std::printf("y %.3f p %.1f exact %.1f\n", y, p, exact);
    }
    e.l2 = std::sqrt(num / den);
    return e;
  }

 private:
  int nbins_;
  double range_, cx_, cz_, hw_;
  std::vector<double> psum_, ysum_;
  std::vector<int> cnt_;
  double top_ = 0;
  int samples_ = 0;
};

}  // namespace sphfem::test
