// TetGen behind the project's surface and mesh types.
#include "sphfem/fem/tetrahedralize.h"

#include <tetgen.h>

#include <sstream>
#include <utility>
#include <vector>

namespace sphfem {

namespace {

constexpr const char* kRemesh =
    "remesh the surface more evenly, e.g. in MeshLab: Filters > Remeshing, Simplification and "
    "Reconstruction > Remeshing: Isotropic Explicit Remeshing";

// TetGen reports failures by throwing its exit code (library build, TETLIBRARY).
MeshError tetgen_error(const std::string& file, int code) {
  switch (code) {
    case 1:
      return MeshError(file, "TetGen ran out of memory",
                       "allow larger tetrahedra (raise max_volume) or free memory");
    case 3:
      return MeshError(file, "TetGen found the surface intersecting itself",
                       "remove the intersections, e.g. in MeshLab: Filters > Cleaning and "
                       "Repairing > Select Self Intersecting Faces");
    case 4:
      return MeshError(file, "TetGen found a feature too small for its tolerance", kRemesh);
    case 5:
      return MeshError(file, "TetGen found two facets too close to each other", kRemesh);
    case 10:
      return MeshError(file, "TetGen rejected the surface as input", kRemesh);
    default:
      return MeshError(file, "TetGen failed (internal error " + std::to_string(code) + ")",
                       kRemesh);
  }
}

}  // namespace

std::string tetgen_switches(const TetgenOptions& o) {
  std::ostringstream s;
  s.precision(10);
  s << 'p';  // keep the surface: a piecewise linear complex, not a point cloud
  if (o.quality > 0.0) s << 'q' << o.quality;
  if (o.max_volume > 0.0) s << 'a' << o.max_volume;
  if (o.quiet) s << 'Q';
  return s.str();
}

TetMesh tetrahedralize(const SurfaceMesh& s, const TetgenOptions& o) {
  check_surface(s);
  const std::string file = s.source.empty() ? "surface" : s.source;

  // tetgenio frees its arrays with delete[] on destruction, so they are allocated with new[].
  tetgenio in, out;
  in.firstnumber = 0;
  in.numberofpoints = int(s.x.size());
  in.pointlist = new REAL[3 * s.x.size()];
  for (std::size_t i = 0; i < s.x.size(); ++i)
    for (int a = 0; a < 3; ++a) in.pointlist[3 * i + a] = s.x[i][a];
  in.numberoffacets = int(s.tris.size());
  in.facetlist = new tetgenio::facet[s.tris.size()];
  for (std::size_t t = 0; t < s.tris.size(); ++t) {
    tetgenio::facet& f = in.facetlist[t];
    tetgenio::init(&f);
    f.numberofpolygons = 1;
    f.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&f.polygonlist[0]);
    f.polygonlist[0].numberofvertices = 3;
    f.polygonlist[0].vertexlist = new int[3];
    for (int a = 0; a < 3; ++a) f.polygonlist[0].vertexlist[a] = s.tris[t].v[a];
  }

  std::string sw = tetgen_switches(o);
  std::vector<char> switches(sw.begin(), sw.end());
  switches.push_back('\0');
  try {
    ::tetrahedralize(switches.data(), &in, &out);
  } catch (int code) { throw tetgen_error(file, code); }
  if (out.numberoftetrahedra <= 0 || out.numberofcorners < 4)
    throw MeshError(file, "TetGen produced no tetrahedra", kRemesh);

  // Points no tetrahedron uses (duplicates TetGen set aside) are dropped; the rest are
  // renumbered for locality at the end.
  const int base = out.firstnumber;
  std::vector<int> remap(out.numberofpoints, -1);
  TetMesh m;
  m.tets.resize(out.numberoftetrahedra);
  for (int t = 0; t < out.numberoftetrahedra; ++t)
    for (int a = 0; a < 4; ++a) {
      const int p = out.tetrahedronlist[t * out.numberofcorners + a] - base;
      if (remap[p] < 0) remap[p] = 0;
      m.tets[t].v[a] = p;
    }
  for (int p = 0; p < out.numberofpoints; ++p)
    if (remap[p] == 0) {
      remap[p] = int(m.x.size());
      const REAL* q = out.pointlist + 3 * p;
      m.x.push_back(Vec3d(q[0], q[1], q[2]));
    }
  for (Tet& t : m.tets) {
    for (int& v : t.v) v = remap[v];
    if (tet_volume(m.x[t.v[0]], m.x[t.v[1]], m.x[t.v[2]], m.x[t.v[3]]) < 0.0)
      std::swap(t.v[2], t.v[3]);
  }
  peel_flat_caps(m, o.peel_caps);
  order_for_locality(m);
  try {
    validate_mesh(m, "the tetrahedralisation");
  } catch (const std::runtime_error& e) { throw MeshError(file, e.what(), kRemesh); }
  return m;
}

}  // namespace sphfem
