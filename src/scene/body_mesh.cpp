// A body's rest mesh from its scene entry: a generated shape sized by `resolution`, or a mesh
// file (a surface tetrahedralised by TetGen, or a tetrahedral mesh read as it is).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "scene/messages.h"
#include "sphfem/fem/import.h"
#include "sphfem/fem/tetrahedralize.h"
#include "sphfem/scene/bodies.h"

namespace sphfem {

namespace {

using namespace scene_text;

constexpr double kPi = 3.14159265358979323846;

// Cells along an extent for a cell size near h; at least one.
int cells_along(double extent, double h) { return std::max(1, int(std::lround(extent / h))); }

// Lattice cells of a generated shape, as its generator takes them.
struct ShapeCells {
  int nx = 1, ny = 1, nz = 1;  // box, cloth (ny = 1); tube: layers, rings, segments
  double tets = 0;  // 6 per cell; an upper bound for the cup (its hollow is cut); a double
                    // so that a hostile resolution cannot overflow it
};

ShapeCells shape_cells(const BodySpec& b) {
  ShapeCells c;
  const int n = b.resolution;
  switch (b.shape) {
    case BodyShape::Box: {
      const double h = std::max({b.size.x, b.size.y, b.size.z}) / n;
      c.nx = cells_along(b.size.x, h), c.ny = cells_along(b.size.y, h);
      c.nz = cells_along(b.size.z, h);
      break;
    }
    case BodyShape::Cloth: {
      const double h = std::max(b.size.x, b.size.z) / n;
      c.nx = cells_along(b.size.x, h), c.nz = cells_along(b.size.z, h);
      break;
    }
    case BodyShape::Tube: {
      // Cells of one size h through the wall, along the axis and around the mid-wall circle;
      // the generator needs six segments at least.
      const double h = std::max(b.length, 2.0 * b.radius) / n;
      c.nx = cells_along(b.radius - b.inner_radius, h);
      c.ny = cells_along(b.length, h);
      c.nz = std::max(6, cells_along(kPi * (b.radius + b.inner_radius), h));
      break;
    }
    case BodyShape::Cup: {
      const double h = 2.0 * b.radius / n;  // as make_cup sizes its lattice
      c.nx = c.nz = n;
      c.ny = cells_along(b.thickness, h) + cells_along(b.height - b.thickness, h);
      break;
    }
    case BodyShape::Sphere:
      c.nx = c.ny = c.nz = n;
      break;
    case BodyShape::Mesh:
      return c;
  }
  c.tets = 6.0 * double(c.nx) * double(c.ny) * double(c.nz);
  return c;
}

TetMesh generate(const BodySpec& b, const ShapeCells& c) {
  switch (b.shape) {
    case BodyShape::Box:
      return make_box(b.position - b.size * 0.5, b.position + b.size * 0.5, c.nx, c.ny, c.nz);
    case BodyShape::Cloth:
      return make_cloth(b.position, b.size.x, b.size.z, b.thickness, c.nx, c.nz);
    case BodyShape::Tube:
      return make_tube(b.position, b.inner_radius, b.radius, b.length, c.nz, c.nx, c.ny);
    case BodyShape::Cup:
      return make_cup(b.position, b.inner_radius, b.radius, b.height, b.thickness, b.resolution);
    case BodyShape::Sphere:
      return make_sphere(b.position, b.radius, b.resolution);
    case BodyShape::Mesh:
      break;
  }
  throw std::logic_error("generate: not a generated shape");
}

bool is_tet_mesh_file(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return char(std::tolower(ch)); });
  return ext == ".node" || ext == ".ele" || ext == ".msh";
}

TetMesh read_mesh_file(const BodySpec& b, const std::string& at, const std::string& scene_file) {
  const std::string path = resolve_path(b.file, scene_file);
  try {
    if (is_tet_mesh_file(path)) {
      TetMesh m = load_tet_mesh(path);
      for (Vec3d& x : m.x) x = x * b.scale + b.offset;  // scale > 0 keeps the orientation
      return m;
    }
    SurfaceMesh s = load_surface(path);
    transform(s, b.scale, b.offset);
    // TetGen makes at least volume / max_volume tetrahedra: refuse a bound that would make
    // more than the cap before it spends minutes meshing.
    const double volume = std::fabs(enclosed_volume(s.x, s.tris));
    if (b.max_volume > 0 && volume / b.max_volume > scene::kMaxBodyTets)
      fail(scene_file, at + ".max_volume",
           "the surface encloses " + num(volume) + " m^3, so max_volume " + num(b.max_volume) +
               " m^3 would make more than " + num(volume / b.max_volume) +
               " tetrahedra, more than the limit of " + std::to_string(scene::kMaxBodyTets),
           "set max_volume to at least " + num(volume / scene::kMaxBodyTets) +
               " m^3, or 0 to let TetGen choose");
    TetgenOptions o;
    o.max_volume = b.max_volume;
    o.quality = b.quality;
    o.peel_caps = b.peel_caps;
    return tetrahedralize(s, o);
  } catch (const MeshError& e) {
    // The mesh error already names the mesh file, the problem and the fix.
    throw SceneError(one_line(display_file(scene_file) + ": " + at + ".file: " + e.what()));
  }
}

}  // namespace

ShapeSize shape_size(const BodySpec& b) {
  if (b.shape == BodyShape::Mesh) return {};
  const ShapeCells c = shape_cells(b);
  // In doubles before the + 1: a hostile resolution makes nx INT_MAX (found by UBSan).
  return {(double(c.nx) + 1) * (double(c.ny) + 1) * (double(c.nz) + 1), c.tets};
}

TetMesh body_rest_mesh(const BodySpec& b, const std::string& at, const std::string& scene_file) {
  if (b.shape == BodyShape::Mesh) {
    if (b.file.empty())
      fail(scene_file, at + ".file", "a mesh body needs a file",
           "give the path of a surface (OBJ, PLY, STL) or a tetrahedral mesh (.node/.ele, "
           ".msh), relative to the scene file's folder");
    return read_mesh_file(b, at, scene_file);
  }
  const ShapeCells c = shape_cells(b);
  if (c.tets > scene::kMaxBodyTets)
    fail(scene_file, at + ".resolution",
         "resolution " + std::to_string(b.resolution) + " would make " + num(c.tets) +
             " tetrahedra, more than " + std::to_string(scene::kMaxBodyTets),
         "lower the resolution");
  try {
    return generate(b, c);
  } catch (const std::exception& e) {
    // The parameters were checked before; this is a generator's own refusal.
    fail(scene_file, at, std::string("cannot generate the shape (") + e.what() + ")",
         "check the shape's parameters in docs/scene-format.md");
  }
}

}  // namespace sphfem
