// The fluid's output frame: a snapshot as the point set the VTK and PLY writers take, with the
// arrays `sphfem run` writes (velocity, density, pressure, id, neighbors).
#pragma once

#include "sphfem/io/frame.h"
#include "sphfem/sph/solver.h"

namespace sphfem {

io::PointSet fluid_frame(const FluidSnapshot& s);

}  // namespace sphfem
