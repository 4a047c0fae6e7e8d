// The CPU instantiation of the coupler, the backend factory and the surface builders.
#include "core/exec_cpu.h"
#include "couple/coupler_impl.h"
#include "sphfem/fem/model.h"
#include "sphfem/fem/solver.h"

namespace sphfem {

std::unique_ptr<Coupler> make_cuda_coupler();

std::unique_ptr<Coupler> make_coupler(Backend backend) {
  if (backend == Backend::Cuda) {
    std::string why;
    if (!cuda_available(&why))
      throw std::runtime_error("--backend cuda: " + why + "; run with --backend cpu");
    return make_cuda_coupler();
  }
  return std::make_unique<CouplerT<CpuExec>>();
}

CoupleSurface body_surface(const BodyArrays& a, const BodiesModel& model,
                           std::vector<ContactCoeffs> coeffs) {
  CoupleSurface s;
  s.space = a.space;
  s.nodes = a.nodes;
  s.triangles = a.triangles;
  s.tri = a.surface;
  s.x = a.x;
  s.v = a.v;
  s.mass = a.mass;
  s.pinned = a.pinned;
  s.impulse = a.impulse;
  // tri_offset holds one entry per body and the total last.
  s.tri_offset = model.tri_offset;
  s.coeffs = std::move(coeffs);
  return s;
}

CoupleSurface static_surface(MemSpace space, int nodes, const Vec3* x, int triangles,
                             const Tri* tri, ContactCoeffs coeffs) {
  CoupleSurface s;
  s.space = space;
  s.nodes = nodes;
  s.triangles = triangles;
  s.tri = tri;
  s.x = x;
  s.coeffs = {coeffs};
  return s;
}

}  // namespace sphfem
