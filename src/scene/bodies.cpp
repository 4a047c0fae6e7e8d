// Scene bodies checked against the scene (names, shape parameters, domain, pinned nodes) and
// compiled into the model the FEM solver runs.
#include "sphfem/scene/bodies.h"

#include <algorithm>
#include <cctype>
#include <limits>
#include <map>
#include <stdexcept>

#include "scene/messages.h"
#include "sphfem/fem/import.h"

namespace sphfem {

namespace {

using namespace scene_text;

bool valid_name(const std::string& name) {
  return std::all_of(name.begin(), name.end(),
                     [](unsigned char c) { return std::isalnum(c) || c == '_' || c == '-'; });
}

// Shape parameters the field ranges cannot express, for the shapes that use them.
void check_shape(const BodySpec& b, const std::string& at, const std::string& file) {
  switch (b.shape) {
    case BodyShape::Box:
      for (int k = 0; k < 3; ++k)
        if (!(b.size[k] > 0))
          fail(file, at + ".size",
               std::string("a box needs a positive edge on every axis (") + kAxis[k] + ": " +
                   num(b.size[k]) + ")",
               "give the box's edge lengths in m, e.g. [0.2, 0.1, 0.1]");
      break;
    case BodyShape::Cloth:
      for (int k : {0, 2})
        if (!(b.size[k] > 0))
          fail(file, at + ".size",
               std::string("a cloth needs a positive extent on x and z (") + kAxis[k] + ": " +
                   num(b.size[k]) + ")",
               "give the cloth's extents in m, e.g. [1, 0, 1] (its y extent is thickness)");
      break;
    case BodyShape::Tube:
    case BodyShape::Cup:
      if (!(b.inner_radius < b.radius))
        fail(file, at + ".inner_radius",
             "must be below radius (" + num(b.inner_radius) + " >= " + num(b.radius) + ")",
             "make inner_radius smaller than radius; the wall lies between them");
      if (b.shape == BodyShape::Cup && !(b.thickness < b.height))
        fail(file, at + ".thickness",
             "the cup's bottom must be thinner than its height (" + num(b.thickness) +
                 " >= " + num(b.height) + ")",
             "lower thickness or raise height");
      if (b.shape == BodyShape::Cup && b.resolution < 4)
        fail(file, at + ".resolution",
             "a cup needs at least 4 cells across (got " + std::to_string(b.resolution) + ")",
             "set resolution to 4 or more");
      break;
    case BodyShape::Sphere:
      if (b.resolution < 2)
        fail(file, at + ".resolution",
             "a sphere needs at least 2 cells across (got " + std::to_string(b.resolution) + ")",
             "set resolution to 2 or more");
      break;
    case BodyShape::Mesh:
      if (b.quality != 0 && b.quality < scene::kMinTetgenQuality)
        fail(file, at + ".quality",
             "must be 0 or at least " + num(scene::kMinTetgenQuality) + " (got " + num(b.quality) +
                 "): TetGen may not finish below that",
             "set quality to 0 (off), " + num(scene::kMinTetgenQuality) + " or more, e.g. 1.414");
      break;
  }
}

// The json path of what places the body: `offset` for a mesh, `position` for a shape.
std::string placement(const BodySpec& b, const std::string& at) {
  return at + (b.shape == BodyShape::Mesh ? ".offset" : ".position");
}

void check_inside_domain(const SceneSpec& s, const BodySpec& b, const TetMesh& m,
                         const std::string& at, const std::string& file) {
  const auto [lo, hi] = bounds(m.x);
  const Vec3d dlo = s.domain.lo, dhi = s.domain.hi;
  // Rounding in the inputs is forgiven, as for the fluid's blocks.
  const double tol = 1e-9 * std::max({dhi.x - dlo.x, dhi.y - dlo.y, dhi.z - dlo.z});
  for (int k = 0; k < 3; ++k) {
    const bool below = lo[k]<dlo[k] - tol, above = hi[k]> dhi[k] + tol;
    if (!below && !above) continue;
    const std::string how = below ? num(lo[k]) + " < domain.min " + num(dlo[k])
                                  : num(hi[k]) + " > domain.max " + num(dhi[k]);
    fail(file, placement(b, at),
         std::string("the body reaches outside the domain on ") + kAxis[k] + " (" + how + ")",
         "move or shrink the body to fit inside the domain " + vec(dlo) + " .. " + vec(dhi) +
             " (the body spans " + vec(lo) + " .. " + vec(hi) + ")");
  }
}

std::vector<std::uint8_t> pinned_flags(const BodySpec& b, const TetMesh& m, const std::string& at,
                                       const std::string& file) {
  std::vector<std::uint8_t> pinned(m.x.size(), 0);
  const auto [lo, hi] = bounds(m.x);
  const double tol = 1e-9 * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  for (std::size_t j = 0; j < b.pinned.boxes.size(); ++j) {
    const PinBoxSpec& box = b.pinned.boxes[j];
    const std::string here = indexed(at + ".pinned.boxes", j);
    for (int k = 0; k < 3; ++k)
      if (!(box.lo[k] <= box.hi[k]))
        fail(file, here + ".max",
             std::string("must not be below min (") + kAxis[k] + ": " + num(box.hi[k]) + " < " +
                 num(box.lo[k]) + ")",
             "swap or correct the corners so that min <= max");
    int count = 0;
    for (std::size_t i = 0; i < m.x.size(); ++i) {
      bool in = true;
      for (int k = 0; k < 3; ++k)
        in = in && m.x[i][k] >= box.lo[k] - tol && m.x[i][k] <= box.hi[k] + tol;
      if (in) pinned[i] = 1, ++count;
    }
    if (count == 0)
      fail(file, here,
           "the box " + vec(box.lo) + " .. " + vec(box.hi) + " holds no node of the body",
           "move or enlarge the box onto the body, whose rest nodes span " + vec(lo) + " .. " +
               vec(hi));
  }
  for (std::size_t j = 0; j < b.pinned.nodes.size(); ++j) {
    const int node = b.pinned.nodes[j];
    if (node < 0 || std::size_t(node) >= m.x.size())
      fail(file, indexed(at + ".pinned.nodes", j),
           "node " + std::to_string(node) + " does not exist: the body has " +
               std::to_string(m.x.size()) + " nodes",
           "use indices from 0 to " + std::to_string(m.x.size() - 1));
    pinned[std::size_t(node)] = 1;
  }
  return pinned;
}

}  // namespace

BodyMesh build_body_mesh(const SceneSpec& s, std::size_t index, const std::string& file) {
  const BodySpec& b = s.bodies.at(index);
  const std::string at = indexed("bodies", index);
  BodyMesh out;
  out.mesh = body_rest_mesh(b, at, file);
  check_inside_domain(s, b, out.mesh, at, file);
  out.pinned = pinned_flags(b, out.mesh, at, file);
  return out;
}

void check_bodies(const SceneSpec& s, const std::string& file) {
  std::map<std::string, std::size_t> names;
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    const BodySpec& b = s.bodies[i];
    const std::string at = indexed("bodies", i);
    if (b.name.empty())
      fail(file, at + ".name", "must not be empty",
           "give the body a name, e.g. \"body" + std::to_string(i) + "\"");
    if (!valid_name(b.name))
      fail(file, at + ".name",
           in_quotes(b.name) + " has characters other than letters, digits, '_' and '-'",
           "use a name that can head a column of gauges.csv, e.g. \"body" + std::to_string(i) +
               "\"");
    const auto [it, fresh] = names.emplace(b.name, i);
    if (!fresh)
      fail(file, at + ".name",
           in_quotes(b.name) + " is already the name of " + indexed("bodies", it->second),
           "give each body a different name");
    check_shape(b, at, file);
    build_body_mesh(s, i, file);
  }
}

BodiesModel compile_scene_bodies(const SceneSpec& s) {
  std::vector<BodyModel> bodies;
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    const BodySpec& spec = s.bodies[i];
    const BodyMesh m = build_body_mesh(s, i, s.path);
    try {
      bodies.push_back(compile_body(m.mesh, spec.material, m.pinned, spec.name));
    } catch (const std::runtime_error& e) {
      fail(s.path, indexed("bodies", i), e.what(), "see docs/scene-format.md");
    }
    bodies.back().velocity = spec.velocity;
  }
  FemSettings set;
  set.gravity = s.simulation.gravity;
  set.box = true;  // the tank holds the bodies as it holds the fluid
  set.box_lo = s.domain.lo;
  set.box_hi = s.domain.hi;
  set.friction = s.fem.friction;
  set.cg_tolerance = s.fem.cg_tolerance;
  set.cg_max_iterations = s.fem.cg_max_iterations;
  set.two_level = s.fem.preconditioner == FemPreconditioner::TwoLevel;
  set.rotation_iterations = s.fem.rotation_iterations;
  set.newton_iterations = s.fem.newton_iterations;
  try {
    return compile_bodies(std::move(bodies), set);
  } catch (const std::runtime_error& e) {
    fail(s.path, "fem", e.what(), "see docs/scene-format.md");
  }
}

int nearest_rest_node(const BodiesModel& m, int body, const Vec3d& p) {
  const BodyModel& b = m.bodies.at(std::size_t(body));
  int best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < b.rest.size(); ++i) {
    const double d = norm2(b.rest[i] - p);
    if (d < best_d) best_d = d, best = int(i);
  }
  return m.node_offset.at(std::size_t(body)) + best;
}

int body_index(const SceneSpec& s, const std::string& name) {
  for (std::size_t i = 0; i < s.bodies.size(); ++i)
    if (s.bodies[i].name == name) return int(i);
  return -1;
}

}  // namespace sphfem
