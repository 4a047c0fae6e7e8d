// From the frame files' neutral form (io::PointSet) to what the renderers draw.
#pragma once

#include <vector>

#include "sphfem/io/frame.h"
#include "sphfem/render/frame.h"

namespace sphfem::render {

// The triangles (VTK type 5) of a body-surface frame (sim/body_frames.h), one mesh per value
// of the cell array "body" (all one body without it), each with its own vertices and its
// palette colour. Other cell types are skipped.
std::vector<TriangleMesh> body_meshes(const io::PointSet& surface);

// The same for the obstacles' file (obstacles.vtu, cell array "obstacle"), in one grey.
std::vector<TriangleMesh> obstacle_meshes(const io::PointSet& surface);

}  // namespace sphfem::render
