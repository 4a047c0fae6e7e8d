// Validation: every number's range again (for scenes built in code) and the checks across
// fields: the domain, blocks, emitters, bodies, gauges and the solver's own limits.
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "scene/field_checks.h"
#include "scene/messages.h"
#include "sphfem/scene/bodies.h"
#include "sphfem/scene/compile.h"
#include "sphfem/scene/fields.h"
#include "sphfem/scene/limits.h"
#include "sphfem/scene/load.h"
#include "sphfem/scene/obstacles.h"

namespace sphfem {
namespace {

using nlohmann::json;
using scene::check_number;
using scene::example;
using scene::Field;
using scene::FieldType;
using scene::ObjectTable;
using namespace scene_text;

// Range checks of every number again, for scenes built in code rather than parsed.
void check_fields(const ObjectTable& t, const void* owner, const std::string& at,
                  const std::string& file) {
  void* mutable_owner = const_cast<void*>(owner);  // accessors are shared with the reader
  for (const Field& f : t.fields) {
    const std::string here = join(at, f.key);
    switch (f.type) {
      case FieldType::Number:
      case FieldType::Integer:
        check_number(f, f.get(owner).get<double>(), here, file);
        break;
      case FieldType::IntegerList: {
        const json v = f.get(owner);
        for (std::size_t i = 0; i < v.size(); ++i)
          check_number(f, v[i].get<double>(), indexed(here, i), file);
        break;
      }
      case FieldType::Vec3: {
        const json v = f.get(owner);
        for (std::size_t i = 0; i < 3; ++i) {
          if (!std::isfinite(v[i].get<double>()))
            fail(file, indexed(here, i),
                 "must be a finite number (got " + num(v[i].get<double>()) + ")",
                 "use three ordinary numbers, e.g. " + example(f));
        }
        break;
      }
      case FieldType::Object:
        check_fields(*f.table, f.child(mutable_owner), here, file);
        break;
      case FieldType::ObjectArray:
        for (std::size_t i = 0; i < f.count(owner); ++i)
          check_fields(*f.table, f.element(mutable_owner, i), indexed(here, i), file);
        break;
      default:
        break;
    }
  }
}

// How far a disc of radius r perpendicular to unit vector d extends along axis k.
double disc_reach(const Vec3d& d, double r, int k) {
  return r * std::sqrt(std::max(0.0, 1.0 - d[k] * d[k]));
}

// A node gauge follows a body by name; the other kinds sample the fluid and take no body.
void check_gauge_body(const SceneSpec& s, const GaugeSpec& g, const std::string& at,
                      const std::string& path) {
  if (g.kind != GaugeKind::Node) {
    if (!g.body.empty())
      fail(path, at + ".body", "only node gauges follow a body",
           "remove body, or set type to \"node\" to follow a node of " + in_quotes(g.body));
    return;
  }
  std::vector<std::string> bodies;
  for (const BodySpec& b : s.bodies) bodies.push_back(b.name);
  const std::string choose = bodies.empty()
                                 ? "add the body to bodies, or use a pressure or height gauge"
                                 : "set body to one of " + in_quotes_list(bodies);
  if (g.body.empty()) fail(path, at + ".body", "a node gauge needs the body it follows", choose);
  if (body_index(s, g.body) < 0)
    fail(path, at + ".body", "there is no body named " + in_quotes(g.body), choose);
}

// The gauges.csv columns the scene names (each body's energies, each gauge's values) must
// differ, or two quantities would share a heading.
void check_gauge_columns(const SceneSpec& s, const std::string& path) {
  std::map<std::string, std::string> owner;
  for (std::size_t i = 0; i < s.bodies.size(); ++i)
    for (const char* suffix : {"_kinetic_energy", "_elastic_energy"})
      owner.emplace(s.bodies[i].name + suffix, indexed("bodies", i));
  for (std::size_t i = 0; i < s.gauges.size(); ++i) {
    const GaugeSpec& g = s.gauges[i];
    std::vector<std::string> columns = {g.name};
    if (g.kind == GaugeKind::Node) columns = {g.name + "_dx", g.name + "_dy", g.name + "_dz"};
    for (const std::string& c : columns) {
      const auto [it, fresh] = owner.emplace(c, indexed("gauges", i));
      if (!fresh)
        fail(path, indexed("gauges", i) + ".name",
             "its column " + in_quotes(c) + " is also a column of " + it->second,
             "rename the gauge");
    }
  }
}

}  // namespace

void validate_scene(const SceneSpec& s, const std::string& path) {
  check_fields(scene::scene_table(), &s, "", path);

  const Vec3d lo = s.domain.lo, hi = s.domain.hi;
  const std::string box = vec(lo) + " .. " + vec(hi);
  for (int k = 0; k < 3; ++k) {
    if (!(lo[k] < hi[k]))
      fail(path, "domain.max",
           std::string("must be greater than domain.min on every axis (") + kAxis[k] + ": " +
               num(hi[k]) + " <= " + num(lo[k]) + ")",
           std::string("raise domain.max or lower domain.min on ") + kAxis[k]);
  }
  // Comparisons against walls forgive rounding in the inputs, far below a particle spacing.
  const double tol = 1e-9 * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  auto outside = [&](const Vec3d& p, int k) { return p[k] < lo[k] - tol || p[k] > hi[k] + tol; };
  auto wall_text = [&](const Vec3d& p, int k) {
    return p[k] < lo[k] ? num(p[k]) + " < domain.min " + num(lo[k])
                        : num(p[k]) + " > domain.max " + num(hi[k]);
  };

  if (s.simulation.dt_min > s.simulation.dt_max)
    fail(path, "simulation.dt_min",
         "must not exceed simulation.dt_max (" + num(s.simulation.dt_min) + " > " +
             num(s.simulation.dt_max) + ")",
         "lower simulation.dt_min or raise simulation.dt_max");

  const double spacing = 2.0 * s.fluid.particle_radius;
  const double narrowest = std::min({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  // The particle size only matters to a scene that has fluid.
  for (int k = 0; k < 3 && s.has_fluid(); ++k) {
    const double cells = (hi[k] - lo[k]) / spacing;
    if (cells < scene::kMinDomainSpacings * (1 - 1e-9))
      fail(path, "fluid.particle_radius",
           std::string("the domain is only ") + num(cells) + " particle spacings wide on " +
               kAxis[k] + " (" + num(hi[k] - lo[k]) + " m at spacing " + num(spacing) +
               " m), fewer than " + num(scene::kMinDomainSpacings),
           "set particle_radius to at most " + num(narrowest / (2.0 * scene::kMinDomainSpacings)) +
               " m or widen the domain on " + kAxis[k]);
  }

  if (!s.has_fluid() && s.bodies.empty())
    fail(path, "fluid",
         "the scene has no fluid (fluid.blocks and fluid.emitters are both empty) and no bodies",
         "add a box to fluid.blocks, e.g. {\"min\": " + vec(lo) + ", \"max\": " +
             vec(lo + (hi - lo) * 0.25) + "}, an emitter to fluid.emitters or a body to bodies");

  for (std::size_t i = 0; i < s.fluid.blocks.size(); ++i) {
    const FluidBlockSpec& b = s.fluid.blocks[i];
    const std::string at = indexed("fluid.blocks", i);
    for (int k = 0; k < 3; ++k) {
      if (!(b.lo[k] < b.hi[k]))
        fail(path, at + ".max",
             std::string("must be greater than min on every axis (") + kAxis[k] + ": " +
                 num(b.hi[k]) + " <= " + num(b.lo[k]) + ")",
             "swap or correct the corners so that min < max");
    }
    for (int k = 0; k < 3; ++k) {
      if (outside(b.lo, k))
        fail(path, at + ".min",
             std::string("the block lies outside the domain on ") + kAxis[k] + " (" +
                 wall_text(b.lo, k) + ")",
             "move or shrink the block to fit inside the domain " + box);
      if (outside(b.hi, k))
        fail(path, at + ".max",
             std::string("the block lies outside the domain on ") + kAxis[k] + " (" +
                 wall_text(b.hi, k) + ")",
             "move or shrink the block to fit inside the domain " + box);
    }
    for (int k = 0; k < 3; ++k) {
      const double size = b.hi[k] - b.lo[k];
      if (size < spacing * (1 - 1e-9))
        fail(path, at,
             "the block is " + num(size) + " m thick on " + kAxis[k] +
                 ", less than one particle spacing (" + num(spacing) + " m = 2 * particle_radius)",
             "make the block at least " + num(spacing) +
                 " m on every axis or lower fluid.particle_radius");
    }
  }

  for (std::size_t i = 0; i < s.fluid.emitters.size(); ++i) {
    const EmitterSpec& e = s.fluid.emitters[i];
    const std::string at = indexed("fluid.emitters", i);
    const double length = norm(e.direction);
    if (!(length > 0))
      fail(path, at + ".direction", "must not be the zero vector",
           "give the direction of the outflow, e.g. [0, -1, 0]");
    const Vec3d d = e.direction / length;
    for (int k = 0; k < 3; ++k) {
      if (outside(e.position, k))
        fail(path, at + ".position",
             std::string("the nozzle centre lies outside the domain on ") + kAxis[k] + " (" +
                 wall_text(e.position, k) + ")",
             "move the emitter inside the domain " + box);
    }
    for (int k = 0; k < 3; ++k) {
      const double reach = disc_reach(d, e.radius, k);
      const Vec3d low = e.position - Vec3d(k == 0, k == 1, k == 2) * reach;
      const Vec3d high = e.position + Vec3d(k == 0, k == 1, k == 2) * reach;
      const Vec3d& out = outside(low, k) ? low : high;
      if (outside(low, k) || outside(high, k))
        fail(path, at + ".position",
             "the nozzle disc (radius " + num(e.radius) + " m) reaches outside the domain on " +
                 kAxis[k] + " (" + wall_text(out, k) + ")",
             "move the emitter at least " + num(reach) +
                 " m away from that wall, or reduce its "
                 "radius");
    }
    if (e.radius < spacing * (1 - 1e-9))
      fail(path, at + ".radius",
           num(e.radius) + " m is smaller than one particle spacing (" + num(spacing) +
               " m = 2 * particle_radius)",
           "use a radius of at least " + num(spacing) + " m or lower fluid.particle_radius");
    if (!(e.start < e.end))
      fail(path, at + ".end",
           "must be later than start (end " + num(e.end) + " <= start " + num(e.start) + ")",
           "set end greater than start, or leave end out to emit until the run ends");
  }

  // Counts and memory before anything is built: the bodies below are.
  check_limits(s, path, available_memory_bytes());
  check_bodies(s, path);
  compile_obstacles(s, path);

  std::map<std::string, std::size_t> names;
  for (std::size_t i = 0; i < s.gauges.size(); ++i) {
    const GaugeSpec& g = s.gauges[i];
    const std::string at = indexed("gauges", i);
    if (g.name.empty())
      fail(path, at + ".name", "must not be empty",
           "give the gauge a name, e.g. \"gauge" + std::to_string(i) + "\"");
    auto [it, fresh] = names.emplace(g.name, i);
    if (!fresh)
      fail(path, at + ".name",
           in_quotes(g.name) + " is already the name of " + indexed("gauges", it->second),
           "give each gauge a different name");
    for (int k = 0; k < 3; ++k) {
      // A height gauge measures the surface along y itself, so only x and z must be inside.
      if (g.kind == GaugeKind::Height && k == 1) continue;
      if (outside(g.position, k))
        fail(path, at + ".position",
             std::string("the gauge lies outside the domain on ") + kAxis[k] + " (" +
                 wall_text(g.position, k) + ")",
             "put the gauge inside the domain " + box);
    }
    check_gauge_body(s, g, at, path);
  }
  check_gauge_columns(s, path);

  // Solver-specific checks (time step vs CFL) come from the solver that knows its limits.
  const std::string solver_problem = s.has_fluid() ? check_solver_settings(s) : "";
  if (!solver_problem.empty())
    throw SceneError(one_line(display_file(path) + ": " + solver_problem));
}

}  // namespace sphfem
