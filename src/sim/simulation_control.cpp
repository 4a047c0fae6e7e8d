// Control of a Simulation between steps: emitters on and off, pinned nodes moved
// (include/sphfem/sim/simulation.h).
#include <stdexcept>
#include <string>

#include "sphfem/sim/simulation.h"

namespace sphfem {

namespace {

FluidSolver& emitting_fluid(FluidSolver* fluid) {
  if (!fluid) throw std::out_of_range("the scene has no fluid, so no emitters (fluid.emitters)");
  return *fluid;
}

}  // namespace

void Simulation::set_emitter_enabled(int e, bool enabled) {
  emitting_fluid(fluid_.get()).set_emitter_enabled(e, enabled);
}

bool Simulation::emitter_enabled(int e) const {
  return emitting_fluid(fluid_.get()).emitter_enabled(e);
}

std::vector<int> Simulation::pinned_nodes(int body) const {
  const BodiesModel& m = bodies_model();
  if (body < 0 || std::size_t(body) >= m.bodies.size())
    throw std::out_of_range("body " + std::to_string(body) + ": the scene has " +
                            std::to_string(m.bodies.size()) + " bodies, numbered from 0");
  std::vector<int> nodes;
  for (int i = m.node_offset[std::size_t(body)]; i < m.node_offset[std::size_t(body) + 1]; ++i)
    if (m.pinned[std::size_t(i)]) nodes.push_back(i);
  return nodes;
}

void Simulation::move_pinned(const std::vector<int>& nodes, const std::vector<Vec3d>& x) {
  if (nodes.size() != x.size())
    throw std::invalid_argument("move_pinned: " + std::to_string(nodes.size()) + " nodes and " +
                                std::to_string(x.size()) + " positions; give one per node");
  for (int i : nodes)
    if (i < 0 || i >= bodies_model().nodes || !bodies_model().pinned[std::size_t(i)])
      throw std::invalid_argument("move_pinned: node " + std::to_string(i) +
                                  (i < 0 || i >= bodies_model().nodes
                                       ? " is out of range (the bodies have " +
                                             std::to_string(bodies_model().nodes) + " nodes)"
                                       : " is not pinned; pin it in the scene (bodies[].pinned)"));
  if (nodes.empty()) return;
  BodySnapshot b;
  bodies_->snapshot(b);
  for (std::size_t k = 0; k < nodes.size(); ++k) b.x[std::size_t(nodes[k])] = Vec3(x[k]);
  // Pinned nodes keep zero velocity: the move is a displacement between steps.
  bodies_->set_positions(b.x);
  if (coupling_) coupling_->bodies_moved();
}

}  // namespace sphfem
