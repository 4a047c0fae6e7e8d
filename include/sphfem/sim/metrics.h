// What gauges.csv reports about one frame: whole-fluid measures and the scene's probes.
#pragma once

#include <vector>

#include "sphfem/scene/spec.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

struct FrameMetrics {
  double front_x = 0;             // m, largest x + radius of particles with >= 5 neighbours
  double max_density_error = 0;   // max over particles of max(rho/rho0 - 1, 0)
  double mean_density_error = 0;  // mean of the same
  double kinetic_energy = 0;      // J
  double momentum[3] = {0, 0, 0}; // kg m/s
  std::vector<double> probes;     // one per fluid gauge (pressure, height): Pa or m
};

// What gauges.csv reports about the bodies in one frame.
struct BodyMetrics {
  std::vector<double> kinetic_energy, elastic_energy;  // J, one per body
  std::vector<Vec3d> displacement;                     // m, one per node gauge
};

// Particles with fewer neighbours than this are spray and do not define the front or heights.
constexpr int kMinBulkNeighbors = 5;

// Node gauges are skipped here: they follow bodies (BodyMetrics).
FrameMetrics compute_metrics(const FluidSnapshot& s, const FluidModel& m,
                             const std::vector<GaugeSpec>& gauges, const DomainSpec& domain);

}  // namespace sphfem
