// Kinetic and elastic energy of each body separately, for the per-body gauge columns; the
// solver's own kinetic_energy() and elastic_energy() sum over all bodies.
#pragma once

#include <vector>

#include "sphfem/fem/mat3.h"
#include "sphfem/fem/model.h"
#include "sphfem/fem/solver.h"

namespace sphfem {

// Measures snapshots of one model on the host. Element rotations are extracted from the
// positions (as the solver's elastic_energy() does) starting from those of the last call,
// so that successive frames converge in a few iterations.
class BodyEnergyMeter {
 public:
  explicit BodyEnergyMeter(const BodiesModel& model);

  // One value per body: 1/2 sum m v^2 (J) and sum V (mu |eps|^2 + lambda/2 tr(eps)^2) (J).
  void measure(const BodySnapshot& s, std::vector<double>& kinetic, std::vector<double>& elastic);

  // The rotations the next call starts from: part of a run's checkpoint, so that a resumed
  // run measures the same bits.
  const std::vector<Quat>& rotations() const { return rot_; }
  void set_rotations(const std::vector<Quat>& r) {
    if (r.size() == rot_.size()) rot_ = r;
  }

 private:
  const BodiesModel& model_;
  std::vector<Quat> rot_;
  std::vector<double> element_energy_;
};

}  // namespace sphfem
