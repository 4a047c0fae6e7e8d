// Scene -> RayCouplingSettings: the coupling method, skin, tank faces and contact
// coefficients a scene asks for.
#include "sphfem/scene/compile.h"

namespace sphfem {

RayCouplingSettings ray_coupling_settings(const SceneSpec& scene) {
  RayCouplingSettings cs;
  cs.rays = scene.coupling.method == CouplingMethod::RayTraced;
  // The baseline's samples stand for the bodies; the tank keeps its own samples.
  cs.near_surface = cs.rays && scene.coupling.near_surface_density;
  cs.implicit_exchange = scene.coupling.implicit_exchange;
  cs.skin = Real(scene.coupling.skin * scene.fluid.particle_radius);
  cs.tank = cs.rays && scene.coupling.tank_rays;
  cs.tank_lo = Vec3(scene.domain.lo);
  cs.tank_hi = Vec3(scene.domain.hi);
  cs.open_top = scene.domain.open_top;
  cs.wall = ContactCoeffs{Real(scene.coupling.wall_restitution), Real(scene.coupling.wall_slip)};
  for (const BodySpec& b : scene.bodies)
    cs.body.push_back(ContactCoeffs{Real(b.restitution), Real(b.slip)});
  cs.rebuild_quality = scene.coupling.rebuild_quality;
  return cs;
}

}  // namespace sphfem
