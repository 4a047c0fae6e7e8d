// The fluid solver behind one interface for every backend. The physics is written once in
// src/sph/stages.h and instantiated for the CPU (solver_cpu.cpp) and CUDA (solver_cuda.cu).
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "sphfem/core/backend.h"
#include "sphfem/sph/model.h"

namespace sphfem {

// A run that cannot go on (NaN, blow-up); the message says at which step and what to change.
struct SimulationError : std::runtime_error {
  long step;
  SimulationError(long step_, const std::string& what) : std::runtime_error(what), step(step_) {}
};

enum class Phase { Neighbors, Density, Divergence, Forces, Pressure, Integrate, Emit, Count };
const char* phase_name(Phase p);

struct Profile {
  double ms[int(Phase::Count)] = {};
  long steps = 0;
  void clear() { *this = Profile(); }
};

struct StepInfo {
  double dt = 0;
  int pressure_iterations = 0;
  int divergence_iterations = 0;
  // DFSPH: mean residual of the density solve over fluid and wall samples: relative
  // compression, or expansion a particle's remaining pressure still holds open.
  double density_error = 0;
  int clamped = 0;  // particles the last-resort box had to stop this step
  int emitted = 0;
};

struct FluidSnapshot {
  int n = 0;
  std::vector<Vec3> x, v;
  std::vector<Real> rho, p;
  std::vector<std::uint32_t> id;
  std::vector<int> neighbors;  // fluid neighbours within the support, self included
};

class FluidSolver {
 public:
  virtual ~FluidSolver() = default;
  virtual int count() const = 0;
  virtual double time() const = 0;
  virtual long steps() const = 0;
  // One step of at most dt_limit seconds (and the CFL limit). Throws SimulationError.
  virtual StepInfo step(double dt_limit) = 0;
  virtual void snapshot(FluidSnapshot& out) = 0;
  virtual const Profile& profile() const = 0;
  virtual void reset_profile() = 0;
  virtual const FluidModel& model() const = 0;
};

// Throws std::runtime_error when the backend is not usable here (e.g. CUDA without a GPU).
std::unique_ptr<FluidSolver> make_fluid_solver(const FluidModel& model, Backend backend);

}  // namespace sphfem
