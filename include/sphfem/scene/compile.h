// Where a scene becomes models: the one place that reads a SceneSpec for the physics parts
// (sph, fem, couple), which never include scene/. The bodies' model is compile_scene_bodies in
// scene/bodies.h, included here.
#pragma once

#include <string>

#include "sphfem/couple/ray_coupling.h"
#include "sphfem/scene/bodies.h"
#include "sphfem/scene/spec.h"
#include "sphfem/sph/model.h"

namespace sphfem {

// Builds the fluid model; throws std::runtime_error for inconsistent input the loader cannot
// see.
FluidModel compile_fluid(const SceneSpec& scene);

// Stiffness the scene asks for, or one derived from the fastest expected speed (c = 10 v).
double wcsph_stiffness(const SceneSpec& scene);

// Largest stable WCSPH step for a speed bound v (acoustic CFL).
double wcsph_dt_limit(const SceneSpec& scene, double v);

// Checks that need the solver's knowledge (time step against CFL). Returns "" when fine,
// else a one-line message "<json.path>: <what>; <fix>".
std::string check_solver_settings(const SceneSpec& scene);

// The coupling settings a scene asks for.
RayCouplingSettings ray_coupling_settings(const SceneSpec& scene);

}  // namespace sphfem
