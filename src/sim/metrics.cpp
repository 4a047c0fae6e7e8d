#include "sphfem/sim/metrics.h"

#include <algorithm>
#include <cmath>

namespace sphfem {

namespace {

// Shepard-normalised SPH interpolation of pressure at a point (0 where no fluid is near).
double pressure_at(const FluidSnapshot& s, const FluidModel& m, const Vec3d& at) {
  const SphParams& P = m.params;
  double num = 0, den = 0;
  for (int i = 0; i < s.n; ++i) {
    const Vec3d r = at - Vec3d(s.x[i]);
    const double r2 = norm2(r);
    if (r2 >= double(P.h2)) continue;
    const double w = double(P.mass) / double(s.rho[i]) * double(P.kernel.W(Real(std::sqrt(r2))));
    num += w * s.p[i];
    den += w;
  }
  return den > 0 ? num / den : 0.0;
}

// Height of the water column above the floor at (x, z): the top of the highest bulk
// particle within one spacing horizontally.
double height_at(const FluidSnapshot& s, const FluidModel& m, const Vec3d& at, double floor_y) {
  const double d = m.params.spacing;
  double top = floor_y;
  for (int i = 0; i < s.n; ++i) {
    if (s.neighbors[i] < kMinBulkNeighbors) continue;
    if (std::fabs(s.x[i].x - at.x) > d || std::fabs(s.x[i].z - at.z) > d) continue;
    top = std::max(top, double(s.x[i].y) + 0.5 * d);
  }
  return top - floor_y;
}

}  // namespace

FrameMetrics compute_metrics(const FluidSnapshot& s, const FluidModel& m,
                             const std::vector<GaugeSpec>& gauges, const DomainSpec& domain) {
  FrameMetrics f;
  const double mass = m.params.mass, rho0 = m.params.rho0, r = 0.5 * m.params.spacing;
  f.front_x = domain.lo.x;
  double err_sum = 0;
  for (int i = 0; i < s.n; ++i) {
    const Vec3d v(s.v[i]);
    f.kinetic_energy += 0.5 * mass * norm2(v);
    f.momentum[0] += mass * v.x;
    f.momentum[1] += mass * v.y;
    f.momentum[2] += mass * v.z;
    const double err = std::max(0.0, double(s.rho[i]) / rho0 - 1.0);
    f.max_density_error = std::max(f.max_density_error, err);
    err_sum += err;
    if (s.neighbors[i] >= kMinBulkNeighbors) f.front_x = std::max(f.front_x, double(s.x[i].x) + r);
  }
  f.mean_density_error = s.n ? err_sum / s.n : 0.0;
  for (const GaugeSpec& g : gauges)
    if (g.kind != GaugeKind::Node)
      f.probes.push_back(g.kind == GaugeKind::Pressure ? pressure_at(s, m, g.position)
                                                       : height_at(s, m, g.position, domain.lo.y));
  return f;
}

}  // namespace sphfem
