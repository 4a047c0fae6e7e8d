// A scene's gauges as time series in memory (include/sphfem/sim/gauge_series.h).
#include "sphfem/sim/gauge_series.h"

#include <stdexcept>

#include "sphfem/scene/bodies.h"
#include "sphfem/sim/metrics.h"

namespace sphfem {

GaugeSeries::GaugeSeries(Simulation& sim) : sim_(sim) {
  const SceneSpec& scene = sim.scene();
  columns_ = {"time",
              "step",
              "n_fluid",
              "fluid_front_x",
              "max_density_error",
              "mean_density_error",
              "kinetic_energy",
              "momentum_x",
              "momentum_y",
              "momentum_z",
              "inside_bodies"};
  for (const GaugeSpec& g : scene.gauges) {
    if (g.kind != GaugeKind::Node) {
      columns_.push_back(g.name);
      gauge_node_.push_back(-1);
      continue;
    }
    for (const char* axis : {"_dx", "_dy", "_dz"}) columns_.push_back(g.name + axis);
    const int b = body_index(scene, g.body);
    if (b < 0)
      throw std::runtime_error("gauge '" + g.name + "' follows body '" + g.body +
                               "', which the scene does not have");
    gauge_node_.push_back(nearest_rest_node(sim.bodies_model(), b, g.position));
  }
  for (const BodySpec& b : scene.bodies) {
    columns_.push_back(b.name + "_kinetic_energy");
    columns_.push_back(b.name + "_elastic_energy");
  }
  if (sim.bodies()) meter_.emplace_back(sim.bodies_model());
  values_.resize(columns_.size());
}

void GaugeSeries::record() {
  FluidSnapshot f;
  sim_.snapshot(f);
  BodySnapshot b;
  if (sim_.bodies()) sim_.bodies()->snapshot(b);
  record(f, b);
}

void GaugeSeries::record(const FluidSnapshot& f, const BodySnapshot& b) {
  const SceneSpec& scene = sim_.scene();
  const FrameMetrics m = compute_metrics(f, sim_.fluid_model(), scene.gauges, scene.domain);
  std::vector<double> row = {sim_.time(),
                             double(sim_.steps()),
                             double(f.n),
                             m.front_x,
                             m.max_density_error,
                             m.mean_density_error,
                             m.kinetic_energy,
                             m.momentum[0],
                             m.momentum[1],
                             m.momentum[2],
                             double(sim_.count_inside(f.x, b.x))};
  const BodiesModel& bodies = sim_.bodies_model();
  std::size_t probe = 0;
  for (int node : gauge_node_) {
    if (node < 0) {
      row.push_back(m.probes.at(probe++));
      continue;
    }
    const Vec3d d(b.x.at(std::size_t(node)) - bodies.x0[std::size_t(node)]);
    row.insert(row.end(), {d.x, d.y, d.z});
  }
  if (!meter_.empty()) {
    std::vector<double> kinetic, elastic;
    meter_[0].measure(b, kinetic, elastic);
    for (std::size_t k = 0; k < kinetic.size(); ++k) {
      row.push_back(kinetic[k]);
      row.push_back(elastic[k]);
    }
  }
  for (std::size_t c = 0; c < columns_.size(); ++c) values_[c].push_back(row.at(c));
}

void GaugeSeries::clear() {
  for (std::vector<double>& v : values_) v.clear();
  // The meter's warm start goes too, so a cleared series measures as a new one would.
  if (!meter_.empty()) {
    meter_.clear();
    meter_.emplace_back(sim_.bodies_model());
  }
}

}  // namespace sphfem
