// Per-body energies on the host, with the element math of the solver (fem/corotated.h).
#include "sphfem/fem/energy.h"

#include "fem/corotated.h"
#include "fem/polar.h"

namespace sphfem {

namespace {
constexpr int kRotationIterations = 30;  // the iteration stops early once converged
}

BodyEnergyMeter::BodyEnergyMeter(const BodiesModel& model)
    : model_(model), rot_(std::size_t(model.elements), Quat::identity()) {}

void BodyEnergyMeter::measure(const BodySnapshot& s, std::vector<double>& kinetic,
                              std::vector<double>& elastic) {
  const BodiesModel& m = model_;
  const std::size_t bodies = m.bodies.size();
  kinetic.assign(bodies, 0.0);
  elastic.assign(bodies, 0.0);
  for (std::size_t b = 0; b < bodies; ++b) {
    double ek = 0, ee = 0;
    // Per element, then summed in element order: the same bits for any thread count.
    element_energy_.resize(m.tets.size());
    for (int i = m.node_offset[b]; i < m.node_offset[b + 1]; ++i)
      ek += 0.5 * double(m.mass[i]) * double(norm2(s.v[i]));
    const int t0 = m.tet_offset[b], t1 = m.tet_offset[b + 1];
#pragma omp parallel for schedule(static)
    for (int t = t0; t < t1; ++t) {
      const Tet& tet = m.tets[t];
      const Vec3 xs[4] = {s.x[tet.v[0]], s.x[tet.v[1]], s.x[tet.v[2]], s.x[tet.v[3]]};
      const Vec3 g[3] = {m.grad[3 * t], m.grad[3 * t + 1], m.grad[3 * t + 2]};
      rot_[t] =
          fem::extract_rotation(fem::deformation_gradient(xs, g), rot_[t], kRotationIterations);
      const Mat3 R = rot_[t].matrix();
      const Vec3 P[3] = {R * g[0], R * g[1], R * g[2]};
      element_energy_[t] = double(fem::corotated_energy(xs, P, m.mu_vol[t], m.lambda_vol[t]));
    }
    for (int t = t0; t < t1; ++t) ee += element_energy_[t];
    kinetic[b] = ek;
    elastic[b] = ee;
  }
}

}  // namespace sphfem
