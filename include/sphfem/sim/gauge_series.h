// A scene's gauges as time series in memory, for programs that step a Simulation themselves
// (the Python module): each record() measures the present state under the column names
// gauges.csv uses (README), so that a series and a run's file can be compared column by column.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "sphfem/fem/energy.h"
#include "sphfem/sim/simulation.h"

namespace sphfem {

// Columns: time, step, n_fluid, fluid_front_x, max_density_error, mean_density_error,
// kinetic_energy, momentum_x/y/z, inside_bodies; one per fluid gauge of the scene (its name)
// and three per node gauge (<name>_dx/dy/dz); <body>_kinetic_energy and <body>_elastic_energy
// per body. The step-averaged columns of gauges.csv (iterations, timings, leaks crossed since
// the last frame, fluid forces) belong to the run loop and are not here.
class GaugeSeries {
 public:
  // Throws std::runtime_error for a node gauge following a body the scene does not have.
  explicit GaugeSeries(Simulation& sim);

  const std::vector<std::string>& columns() const { return columns_; }
  // Values of column c, one per record().
  const std::vector<double>& column(std::size_t c) const { return values_.at(c); }
  std::size_t rows() const { return values_.empty() ? 0 : values_[0].size(); }

  // Measures the simulation's present state; the snapshots must be of it (taken by the caller,
  // who usually wants them too). body may be empty for a scene without bodies.
  void record(const FluidSnapshot& fluid, const BodySnapshot& body);
  // The same, taking the snapshots itself.
  void record();
  void clear();

 private:
  Simulation& sim_;
  std::vector<std::string> columns_;
  std::vector<std::vector<double>> values_;  // per column
  std::vector<int> gauge_node_;              // per scene gauge: followed node, -1 for fluid
  std::vector<BodyEnergyMeter> meter_;       // one (or none, without bodies)
};

}  // namespace sphfem
