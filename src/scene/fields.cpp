// The scene-file field table: each field of docs/scene-format.md is declared exactly once here.
#include "sphfem/scene/fields.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

namespace sphfem::scene {

bool Range::contains(double v) const {
  if (lo && (lo->inclusive ? v < lo->value : v <= lo->value)) return false;
  if (hi && (hi->inclusive ? v > hi->value : v >= hi->value)) return false;
  return true;
}

std::string Range::text() const {
  std::string s;
  if (lo) s = std::string(lo->inclusive ? ">= " : "> ") + format_number(lo->value);
  if (lo && hi) s += " and ";
  if (hi) s += std::string(hi->inclusive ? "<= " : "< ") + format_number(hi->value);
  return s;
}

Range Range::with_lo(double v, bool inclusive) const {
  Range r = *this;
  r.lo = Bound{v, inclusive};
  return r;
}

Range Range::with_hi(double v, bool inclusive) const {
  Range r = *this;
  r.hi = Bound{v, inclusive};
  return r;
}

const Field* ObjectTable::find(const std::string& key) const {
  for (const Field& f : fields)
    if (f.key == key) return &f;
  return nullptr;
}

std::vector<std::string> ObjectTable::keys() const {
  std::vector<std::string> out;
  for (const Field& f : fields) out.push_back(f.key);
  return out;
}

std::string format_number(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  int precision = 1;
  for (; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  // Whole numbers of moderate size read better in full: 30, not 3e+01.
  const int exponent = v == 0 ? 0 : static_cast<int>(std::floor(std::log10(std::abs(v))));
  if (exponent >= precision && exponent < 15)
    std::snprintf(buf, sizeof buf, "%.*g", exponent + 1, v);
  return buf;
}

std::string format_value(const nlohmann::json& v) {
  if (v.is_number()) return format_number(v.get<double>());
  if (v.is_array()) {
    std::string s = "[";
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + format_value(v[i]);
    return s + "]";
  }
  if (v.is_object()) {
    std::string s = "{";
    bool first = true;
    for (const auto& [key, value] : v.items()) {
      s += (first ? "" : ", ") + nlohmann::json(key).dump() + ": " + format_value(value);
      first = false;
    }
    return s + "}";
  }
  return v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

namespace {

using nlohmann::json;

json vec_to_json(const Vec3d& v) { return json::array({v.x, v.y, v.z}); }
Vec3d vec_from_json(const json& j) {
  return Vec3d(j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>());
}

// Declares the fields of struct T in order, one call per field, and fills their defaults from a
// default-constructed T so that no default is written twice.
template <class T>
class Table {
 public:
  Table(const char* name, const char* description) {
    table_.name = name;
    table_.description = description;
  }

  Table& number(const char* key, double T::*m, const char* unit, Range range, const char* text) {
    Field& f = add(key, FieldType::Number, text);
    f.unit = unit;
    f.range = range;
    f.get = [m](const void* o) { return json(of(o).*m); };
    f.set = [m](void* o, const json& v) { of(o).*m = v.get<double>(); };
    return *this;
  }

  Table& integer(const char* key, int T::*m, const char* unit, Range range, const char* text) {
    Field& f = add(key, FieldType::Integer, text);
    f.unit = unit;
    f.range = range;
    f.get = [m](const void* o) { return json(of(o).*m); };
    f.set = [m](void* o, const json& v) { of(o).*m = static_cast<int>(v.get<double>()); };
    return *this;
  }

  // A list of whole numbers, each within `range`.
  Table& integers(const char* key, std::vector<int> T::*m, Range range, const char* text) {
    Field& f = add(key, FieldType::IntegerList, text);
    f.range = range;
    f.default_value = json::array();
    f.get = [m](const void* o) { return json(of(o).*m); };
    f.set = [m](void* o, const json& v) {
      std::vector<int> values;
      for (const json& x : v) values.push_back(static_cast<int>(x.get<double>()));
      of(o).*m = std::move(values);
    };
    return *this;
  }

  Table& boolean(const char* key, bool T::*m, const char* text) {
    Field& f = add(key, FieldType::Bool, text);
    f.get = [m](const void* o) { return json(of(o).*m); };
    f.set = [m](void* o, const json& v) { of(o).*m = v.get<bool>(); };
    return *this;
  }

  Table& string(const char* key, std::string T::*m, const char* text) {
    Field& f = add(key, FieldType::String, text);
    f.get = [m](const void* o) { return json(of(o).*m); };
    f.set = [m](void* o, const json& v) { of(o).*m = v.get<std::string>(); };
    return *this;
  }

  // Enumerators must be 0, 1, 2, ... in the order of names.
  template <class E>
  Table& choice(const char* key, E T::*m, std::vector<std::string> names, const char* text) {
    Field& f = add(key, FieldType::Enum, text);
    f.choices = names;
    f.get = [m, names](const void* o) {
      return json(names.at(static_cast<std::size_t>(of(o).*m)));
    };
    f.set = [m, names](void* o, const json& v) {
      auto it = std::find(names.begin(), names.end(), v.get<std::string>());
      of(o).*m = static_cast<E>(it - names.begin());
    };
    return *this;
  }

  Table& vec3(const char* key, Vec3d T::*m, const char* unit, const char* text) {
    Field& f = add(key, FieldType::Vec3, text);
    f.unit = unit;
    f.get = [m](const void* o) { return vec_to_json(of(o).*m); };
    f.set = [m](void* o, const json& v) { of(o).*m = vec_from_json(v); };
    return *this;
  }

  template <class C>
  Table& object(const char* key, C T::*m, const ObjectTable& nested, const char* text) {
    Field& f = add(key, FieldType::Object, text);
    f.table = &nested;
    f.child = [m](void* o) -> void* { return &(of(o).*m); };
    return *this;
  }

  template <class C>
  Table& array(const char* key, std::vector<C> T::*m, const ObjectTable& nested, const char* text) {
    Field& f = add(key, FieldType::ObjectArray, text);
    f.table = &nested;
    f.default_value = json::array();
    f.count = [m](const void* o) { return (of(o).*m).size(); };
    f.resize = [m](void* o, std::size_t n) { (of(o).*m).resize(n); };
    f.element = [m](void* o, std::size_t i) -> void* { return &(of(o).*m).at(i); };
    return *this;
  }

  // Rule of the last field beyond type and range, checked by its setter or by validate_scene.
  Table& constraint(const std::string& text) {
    table_.fields.back().constraint = text;
    return *this;
  }

  // Replaces the last field's plain copy; the setter may throw FieldError.
  Table& setter(std::function<void(T&, const json&)> fn) {
    table_.fields.back().set = [fn](void* o, const json& v) { fn(of(o), v); };
    return *this;
  }

  Table& finish(std::function<void(T&, std::size_t)> fn) {
    table_.finish = [fn](void* o, std::size_t index) { fn(of(o), index); };
    return *this;
  }

  ObjectTable build() {
    const T defaults{};
    for (Field& f : table_.fields)
      if (f.get) f.default_value = f.get(&defaults);
    return std::move(table_);
  }

 private:
  static T& of(void* o) { return *static_cast<T*>(o); }
  static const T& of(const void* o) { return *static_cast<const T*>(o); }

  Field& add(const char* key, FieldType type, const char* text) {
    Field f;
    f.key = key;
    f.type = type;
    f.description = text;
    table_.fields.push_back(std::move(f));
    return table_.fields.back();
  }

  ObjectTable table_;
};

const Range kPositive = Range().gt(0);
const Range kNonNegative = Range().ge(0);
const Range kUnit = Range().ge(0).le(1);

const ObjectTable& simulation_table() {
  static const ObjectTable t =
      Table<SimulationSpec>("simulation", "Time span, time stepping and the pressure solver.")
          .number("duration", &SimulationSpec::duration, "s", kPositive, "Simulated time to run.")
          .choice("solver", &SimulationSpec::solver, {"wcsph", "dfsph"},
                  "Pressure solver: weakly compressible SPH (`wcsph`) or divergence-free SPH "
                  "(`dfsph`).")
          .number("dt_max", &SimulationSpec::dt_max, "s", kPositive,
                  "Upper bound of the adaptive time step.")
          .number("dt_min", &SimulationSpec::dt_min, "s", kPositive,
                  "Lower bound of the adaptive time step; a run that needs a smaller step stops "
                  "as unstable.")
          .number("cfl", &SimulationSpec::cfl, "-", Range().gt(0).le(1),
                  "Courant number: fraction of a particle spacing a particle may travel per step.")
          .vec3("gravity", &SimulationSpec::gravity, "m/s^2",
                "Gravitational acceleration; y points up.")
          .number("density_tolerance", &SimulationSpec::density_tolerance, "-", Range().gt(0).lt(1),
                  "DFSPH: target mean relative density error of the pressure solve.")
          .number("divergence_tolerance", &SimulationSpec::divergence_tolerance, "-",
                  Range().gt(0).lt(1),
                  "DFSPH: target mean relative density change per step caused by the velocity "
                  "divergence.")
          .integer("max_iterations", &SimulationSpec::max_iterations, "-", Range().ge(1),
                   "DFSPH: cap on pressure iterations per solve.")
          .build();
  return t;
}

const ObjectTable& block_table() {
  static const ObjectTable t =
      Table<FluidBlockSpec>("fluid.blocks[]",
                            "Boxes filled with fluid particles on a cubic lattice at the start.")
          .vec3("min", &FluidBlockSpec::lo, "m", "Lower corner of the box.")
          .constraint("inside the domain, below `max` on every axis")
          .vec3("max", &FluidBlockSpec::hi, "m", "Upper corner of the box.")
          .constraint("inside the domain, at least one particle spacing above `min`")
          .vec3("velocity", &FluidBlockSpec::velocity, "m/s", "Initial velocity of the fluid.")
          .build();
  return t;
}

const ObjectTable& emitter_table() {
  static const ObjectTable t =
      Table<EmitterSpec>("fluid.emitters[]",
                         "Circular nozzles that add particles while the simulation runs.")
          .vec3("position", &EmitterSpec::position, "m", "Centre of the nozzle.")
          .constraint("nozzle disc inside the domain")
          .vec3("direction", &EmitterSpec::direction, "-",
                "Direction of the outflow; scaled to unit length on load.")
          .constraint("non-zero")
          .setter([](EmitterSpec& e, const json& v) {
            Vec3d d = vec_from_json(v);
            // Scale by the largest component first so huge inputs cannot overflow the norm.
            double big = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
            if (!(big > 0))
              throw FieldError("must not be the zero vector",
                               "give the direction of the outflow, e.g. [0, -1, 0]");
            d = d / big;
            e.direction = d / norm(d);
          })
          .number("radius", &EmitterSpec::radius, "m", kPositive,
                  "Radius of the nozzle disc, perpendicular to `direction`.")
          .constraint("at least one particle spacing")
          .number("speed", &EmitterSpec::speed, "m/s", kPositive,
                  "Speed of the emitted fluid along `direction`.")
          .number("start", &EmitterSpec::start, "s", kNonNegative,
                  "Simulated time at which emission begins.")
          .number("end", &EmitterSpec::end, "s", kNonNegative,
                  "Simulated time at which emission stops.")
          .constraint("greater than `start`")
          .build();
  return t;
}

const ObjectTable& fluid_table() {
  static const ObjectTable t =
      Table<FluidSpec>("fluid", "The fluid's material, its resolution and where it comes from.")
          .number("particle_radius", &FluidSpec::particle_radius, "m", kPositive,
                  "Particle radius; the particle spacing is twice this.")
          .number("rest_density", &FluidSpec::rest_density, "kg/m^3", kPositive,
                  "Density of the fluid at rest.")
          .number("viscosity", &FluidSpec::viscosity, "m^2/s", kNonNegative,
                  "Physical kinematic viscosity.")
          .number("xsph", &FluidSpec::xsph, "-", kUnit,
                  "XSPH velocity smoothing factor; 0 turns it off.")
          .number("artificial_viscosity", &FluidSpec::artificial_viscosity, "-", kNonNegative,
                  "Monaghan artificial viscosity alpha; 0 turns it off.")
          .number("stiffness", &FluidSpec::stiffness, "Pa", kNonNegative,
                  "WCSPH stiffness k in p = k (rho/rho0 - 1); 0 derives it from `max_speed`.")
          .number("max_speed", &FluidSpec::max_speed, "m/s", kNonNegative,
                  "Expected top speed used to derive the stiffness; 0 estimates it from the "
                  "fluid heights.")
          .choice("kernel", &FluidSpec::kernel, {"cubic_spline", "wendland_c2"},
                  "Smoothing kernel.")
          .integer("max_particles", &FluidSpec::max_particles, "-", kNonNegative,
                   "Particle capacity reserved for emitters; 0 estimates it from the emitters.")
          .array("blocks", &FluidSpec::blocks, block_table(),
                 "Initial fluid boxes; lattice points inside a body or within a particle radius of "
                 "its surface are left out. See `fluid.blocks[]`.")
          .array("emitters", &FluidSpec::emitters, emitter_table(),
                 "Inflow nozzles; see `fluid.emitters[]`.")
          .build();
  return t;
}

const ObjectTable& domain_table() {
  static const ObjectTable t =
      Table<DomainSpec>("domain",
                        "The tank: an axis-aligned box whose walls hold the fluid and the bodies.")
          .vec3("min", &DomainSpec::lo, "m", "Inner lower corner of the tank.")
          .vec3("max", &DomainSpec::hi, "m", "Inner upper corner of the tank.")
          .constraint("above `min` on every axis")
          .boolean("open_top", &DomainSpec::open_top,
                   "Tank without a lid; particles above `max` y are still kept inside the "
                   "domain.")
          .build();
  return t;
}

const ObjectTable& output_table() {
  static const ObjectTable t =
      Table<OutputSpec>("output", "What the run writes; gauges are always written.")
          .number("fps", &OutputSpec::fps, "1/s", kPositive,
                  "Frames written per second of simulated time.")
          .boolean("vtu", &OutputSpec::vtu, "Write VTK XML unstructured-grid frames (ParaView).")
          .boolean("ply", &OutputSpec::ply, "Write binary PLY point frames (Houdini, MeshLab).")
          .vec3("camera_position", &OutputSpec::camera_position, "m",
                "Where `sphfem render` and `run --render` look from (written to run.json); "
                "equal to `camera_target` (the default) frames the whole tank automatically.")
          .vec3("camera_target", &OutputSpec::camera_target, "m", "The point the camera looks at.")
          .number("camera_fov", &OutputSpec::camera_fov, "degrees", Range().gt(1).lt(170),
                  "Vertical field of view of the pictures.")
          .number("checkpoint_every", &OutputSpec::checkpoint_every, "s", kNonNegative,
                  "Simulated time between checkpoints (`checkpoint.bin` in the output folder, "
                  "written after the frame that reaches each multiple, and at the end); 0 = "
                  "only at the end. `sphfem run SCENE --out DIR --resume` continues from it.")
          .build();
  return t;
}

const ObjectTable& gauge_table() {
  static const ObjectTable t =
      Table<GaugeSpec>("gauges[]", "Probes sampled at every output frame.")
          .string("name", &GaugeSpec::name,
                  "Column name in the gauge output; empty names become `gauge<i>`, i being the "
                  "position in the list.")
          .constraint("unique")
          .choice("type", &GaugeSpec::kind, {"pressure", "height", "node"},
                  "`pressure` samples the pressure at `position`; `height` measures the fluid "
                  "surface height above `position` x and z; `node` follows the node of `body` "
                  "nearest to `position` at rest and reports its displacement in the columns "
                  "`<name>_dx`, `<name>_dy`, `<name>_dz`.")
          .vec3("position", &GaugeSpec::position, "m",
                "Where the gauge samples; a height gauge uses only x and z.")
          .constraint("inside the domain")
          .string("body", &GaugeSpec::body, "Node gauges: name of the body followed.")
          .constraint("node gauges only, where it must name a body")
          .finish([](GaugeSpec& g, std::size_t index) {
            if (g.name.empty()) g.name = "gauge" + std::to_string(index);
          })
          .build();
  return t;
}

const ObjectTable& material_table() {
  static const ObjectTable t =
      Table<Material>("bodies[].material",
                      "Linear isotropic elastic material of a body and its Rayleigh damping "
                      "D = alpha M + beta K.")
          .number("density", &Material::density, "kg/m^3", kPositive, "Mass density.")
          .number("young", &Material::young, "Pa", kPositive, "Young's modulus E.")
          .number("poisson", &Material::poisson, "-", Range().gt(-1).lt(0.5),
                  "Poisson's ratio; rubber is near 0.45-0.49 (0.5, incompressible, locks linear "
                  "tetrahedra).")
          .number("damping_alpha", &Material::alpha, "1/s", kNonNegative,
                  "Rayleigh mass damping alpha: damps slow motion, a damping ratio of "
                  "alpha / (2 omega) at angular frequency omega.")
          .number("damping_beta", &Material::beta, "s", kNonNegative,
                  "Rayleigh stiffness damping beta: damps fast vibration, a damping ratio of "
                  "beta omega / 2.")
          .build();
  return t;
}

const ObjectTable& pin_box_table() {
  static const ObjectTable t =
      Table<PinBoxSpec>("bodies[].pinned.boxes[]",
                        "Boxes whose nodes (at their rest positions) are held fixed.")
          .vec3("min", &PinBoxSpec::lo, "m", "Lower corner of the box.")
          .constraint("at most `max` on every axis")
          .vec3("max", &PinBoxSpec::hi, "m",
                "Upper corner of the box; equal to `min` on an axis, the box is a plane that "
                "picks the nodes of a flat face.")
          .constraint("the box holds at least one node of the body")
          .build();
  return t;
}

const ObjectTable& pinned_table() {
  static const ObjectTable t =
      Table<PinSpec>("bodies[].pinned",
                     "Nodes held fixed at their rest positions (Dirichlet boundary): those inside "
                     "any of the boxes and those listed.")
          .array("boxes", &PinSpec::boxes, pin_box_table(),
                 "Regions of pinned nodes; see `bodies[].pinned.boxes[]`.")
          .integers("nodes", &PinSpec::nodes, Range().ge(0),
                    "Further pinned nodes by index, from 0, in the order of the body's points in "
                    "`frames/bodies_tets_*.vtu` (counted from the body's first point).")
          .constraint("below the body's node count")
          .build();
  return t;
}

const ObjectTable& body_table() {
  static const ObjectTable t =
      Table<BodySpec>("bodies[]",
                      "Deformable bodies: co-rotated linear FEM on tetrahedra, each a generated "
                      "shape or a mesh file. Bodies feel gravity, the tank's six walls (a lid "
                      "even when `open_top`) and the fluid (see `coupling`).")
          .string("name", &BodySpec::name,
                  "Name in logs, run.json and the gauge columns `<name>_kinetic_energy` and "
                  "`<name>_elastic_energy`; empty names become `body<i>`, i being the position in "
                  "the list.")
          .constraint("unique; letters, digits, `_` and `-`")
          .choice("shape", &BodySpec::shape, {"box", "tube", "cup", "sphere", "cloth", "mesh"},
                  "Generated shape, or `mesh` to read `file`.")
          .vec3("position", &BodySpec::position, "m",
                "Centre of a box, sphere or cloth; centre of the bottom of a tube or cup, which "
                "extend along +y. A mesh is placed by `offset` instead.")
          .constraint("the whole body inside the domain")
          .vec3("size", &BodySpec::size, "m",
                "Box: edge lengths. Cloth: extents along x and z (its y extent is `thickness`).")
          .constraint("box: > 0 on every axis; cloth: > 0 on x and z")
          .number("radius", &BodySpec::radius, "m", kPositive,
                  "Sphere: radius. Tube and cup: outer radius.")
          .number("inner_radius", &BodySpec::inner_radius, "m", kPositive,
                  "Tube and cup: inner radius.")
          .constraint("below `radius`")
          .number("length", &BodySpec::length, "m", kPositive, "Tube: length along +y.")
          .number("height", &BodySpec::height, "m", kPositive,
                  "Cup: height along +y, bottom included.")
          .number("thickness", &BodySpec::thickness, "m", kPositive,
                  "Cloth: thickness along y (one cell). Cup: thickness of the bottom.")
          .constraint("cup: below `height`")
          .integer("resolution", &BodySpec::resolution, "-", Range().ge(1),
                   "Cells across the largest extent (sphere and cup: across the outer "
                   "diameter); the other directions get cells of about the same size. A cell "
                   "holds 6 tetrahedra.")
          .constraint("at most " + std::to_string(kMaxBodyTets) + " tetrahedra")
          .string("file", &BodySpec::file,
                  "Mesh: a closed triangle surface (OBJ, PLY, STL), tetrahedralised with TetGen, "
                  "or a tetrahedral mesh (TetGen `.node`/`.ele`, Gmsh `.msh`) used as it is; a "
                  "relative path is taken from the scene file's folder.")
          .constraint(
              "mesh: required; a surface must be closed, manifold and not intersect "
              "itself")
          .number("scale", &BodySpec::scale, "-", kPositive,
                  "Mesh: factor on the file's coordinates (0.001 for millimetres), applied before "
                  "`offset`.")
          .vec3("offset", &BodySpec::offset, "m", "Mesh: added to the scaled coordinates.")
          .number("max_volume", &BodySpec::max_volume, "m^3", kNonNegative,
                  "Surface meshes: largest tetrahedron volume (TetGen `a`); 0 sets no limit.")
          .number("quality", &BodySpec::quality, "-", kNonNegative,
                  "Surface meshes: largest radius-edge ratio of a tetrahedron (TetGen `q`); "
                  "lower is better shaped but finer; 0 turns quality refinement off.")
          .constraint("0 or at least " + format_number(kMinTetgenQuality))
          .number("peel_caps", &BodySpec::peel_caps, "-", Range().ge(0).lt(0.8),
                  "Surface meshes: remove the flat caps TetGen leaves where the surface is "
                  "nearly flat or ends in a thin lip (elements with two faces on it whose "
                  "smallest height is under this share of their longest edge or of the "
                  "surface's median edge, whichever is shorter), which a floor pressed on "
                  "them flattens to zero volume, and its ears (elements with three faces on "
                  "it whose tip nothing else holds, lower than this share of the median "
                  "edge); 0.3 catches them (the paper's bunny), 0 keeps TetGen's mesh as it "
                  "is.")
          .object("material", &BodySpec::material, material_table(),
                  "Elastic material; see `bodies[].material`.")
          .vec3("velocity", &BodySpec::velocity, "m/s", "Initial velocity of the free nodes.")
          .object("pinned", &BodySpec::pinned, pinned_table(),
                  "Nodes held in place; see `bodies[].pinned`.")
          .number("restitution", &BodySpec::restitution, "-", kUnit,
                  "Fluid contact (ray-traced coupling): share of the normal relative velocity "
                  "reversed (0: the fluid stops on the surface, 1: it bounces back elastically).")
          .number("slip", &BodySpec::slip, "-", kUnit,
                  "Fluid contact: share of the tangential relative velocity kept (1 free slip, 0 "
                  "no slip).")
          .finish([](BodySpec& b, std::size_t index) {
            if (b.name.empty()) b.name = "body" + std::to_string(index);
          })
          .build();
  return t;
}

const ObjectTable& obstacle_key_table() {
  static const ObjectTable t =
      Table<ObstacleKeySpec>(
          "obstacles[].path[]",
          "Poses of a moving obstacle by time. Between two keys the translation goes linearly "
          "and the rotation turns evenly (about one axis when both keys give the same axis, so "
          "a key may add more than half a turn; otherwise along the shortest turn between the "
          "two orientations); before the first key the obstacle holds the first pose, after the "
          "last the last. Fluid and bodies feel the obstacle's velocity.")
          .number("time", &ObstacleKeySpec::time, "s", kNonNegative, "When the pose is reached.")
          .constraint("increasing along the path")
          .vec3("translate", &ObstacleKeySpec::translate, "m",
                "Displacement from where the obstacle is placed (`min`/`max` or `offset`), "
                "applied after the rotation.")
          .vec3("axis", &ObstacleKeySpec::axis, "-", "Axis of the rotation (its direction only).")
          .constraint("not zero when `angle` is not 0")
          .number("angle", &ObstacleKeySpec::angle, "deg", Range(),
                  "Rotation about `axis` through `obstacles[].pivot`, right-handed.")
          .build();
  return t;
}

const ObjectTable& obstacle_table() {
  static const ObjectTable t =
      Table<ObstacleSpec>("obstacles[]",
                          "Obstacles: boxes or triangle surfaces (open ones too: a funnel, a "
                          "slide, a plate) that the fluid and the bodies meet, with no FEM solve; "
                          "they stay put or follow a prescribed `path`. The fluid meets them "
                          "through the ray-traced coupling's rays (as faces of infinite mass, "
                          "like the tank's with `tank_rays`); body nodes stop on them with "
                          "`fem.friction`.")
          .string("name", &ObstacleSpec::name,
                  "Name in logs; empty names become `obstacle<i>`, i being the position in the "
                  "list.")
          .choice("shape", &ObstacleSpec::shape, {"box", "mesh"},
                  "`box` between `min` and `max`, or `mesh` to read `file`.")
          .vec3("min", &ObstacleSpec::lo, "m", "Box: lower corner.")
          .vec3("max", &ObstacleSpec::hi, "m", "Box: upper corner.")
          .constraint("box: above `min` on every axis")
          .string("file", &ObstacleSpec::file,
                  "Mesh: a triangle surface (OBJ, PLY, STL), open or closed; a relative path is "
                  "taken from the scene file's folder.")
          .constraint("mesh: required")
          .number("scale", &ObstacleSpec::scale, "-", kPositive,
                  "Mesh: factor on the file's coordinates, applied before `offset`.")
          .vec3("offset", &ObstacleSpec::offset, "m", "Mesh: added to the scaled coordinates.")
          .number("restitution", &ObstacleSpec::restitution, "-", kUnit,
                  "Fluid contact (ray-traced coupling), as `bodies[].restitution`.")
          .number("slip", &ObstacleSpec::slip, "-", kUnit, "Fluid contact, as `bodies[].slip`.")
          .array("path", &ObstacleSpec::path, obstacle_key_table(),
                 "A prescribed rigid motion (a paddle, a tool, a lift); empty: the obstacle "
                 "stays put. See `obstacles[].path[]`.")
          .constraint("the obstacle inside the domain all along the path")
          .vec3("pivot", &ObstacleSpec::pivot, "m", "The point the path's rotations turn about.")
          .finish([](ObstacleSpec& o, std::size_t index) {
            if (o.name.empty()) o.name = "obstacle" + std::to_string(index);
          })
          .build();
  return t;
}

const ObjectTable& fem_table() {
  static const ObjectTable t =
      Table<FemSpec>("fem",
                     "The implicit FEM solve all bodies share. Bodies step with the fluid's time "
                     "step; without fluid, with steps of at most `simulation.dt_max`, shortened "
                     "evenly so that every frame falls on the end of a step.")
          .number("cg_tolerance", &FemSpec::cg_tolerance, "-", Range().gt(0).lt(1),
                  "Relative residual that ends the conjugate-gradient solve of a step.")
          .integer("cg_max_iterations", &FemSpec::cg_max_iterations, "-", Range().ge(1),
                   "Cap on conjugate-gradient iterations per solve.")
          .choice("preconditioner", &FemSpec::preconditioner, {"block_jacobi", "two_level"},
                  "`block_jacobi`: each node's 3x3 block of the step's matrix. `two_level`: "
                  "with a coarse level beside it, patches about three rest edges across moving "
                  "rigidly, refactored every 10 steps (CPU backend; the CUDA backend keeps "
                  "block Jacobi). Its CG iterations hardly grow with the stiffness: on a "
                  "10 MPa rubber bunny of 22.5k tetrahedra 26.5 a step instead of about 185 "
                  "(docs/design.md, \"Coarse level\"). It holds about 130 B a tetrahedron more "
                  "(the bunny's solver 595 against 464 B) and gains little on soft bodies.")
          .integer("newton_iterations", &FemSpec::newton_iterations, "-", Range().ge(1),
                   "Linearisations per step: 1 is the linearly implicit step; each further one "
                   "re-extracts the element rotations and solves for a correction.")
          .integer("rotation_iterations", &FemSpec::rotation_iterations, "-", Range().ge(1),
                   "Iterations of the element-rotation extraction per linearisation, started "
                   "from the last step's rotations.")
          .number("friction", &FemSpec::friction, "-", kNonNegative,
                  "Coulomb friction coefficient of body nodes sliding on the tank walls and "
                  "the obstacles, and of body surfaces sliding on each other.")
          .boolean("contact", &FemSpec::contact,
                   "Body surfaces meet each other and themselves (a fold, two balls): "
                   "vertex-face and edge-edge contact after each step, pushed apart to "
                   "`contact_gap` with inelastic impulses and `friction`, and the step taken "
                   "again with the contact's impulses (in halves where the surfaces met too "
                   "deep, `contact_halvings`). On in the paper's bunny and low-stiffness tubes, "
                   "which fold onto themselves; off by default, as it costs a search of the "
                   "surfaces every step (docs/validation.md).")
          .number("contact_gap", &FemSpec::contact_gap, "m", kNonNegative,
                  "Distance kept between touching surfaces; 0 is a tenth of the median "
                  "surface edge at rest.")
          .integer("contact_halvings", &FemSpec::contact_halvings, "-", Range().ge(0).le(6),
                   "With `contact`: when surfaces met deeper than half the rest height of the "
                   "elements at the pair, or the step turned an element inside out, the "
                   "bodies' step is taken again in two halves, each of which may halve again, "
                   "this many times at most (the shortest body step is the step / 2^n); 0 "
                   "never halves.")
          .build();
  return t;
}

const ObjectTable& coupling_table() {
  static const ObjectTable t =
      Table<CouplingSpec>("coupling",
                          "How fluid and bodies push each other. Used when the scene has both "
                          "fluid and bodies; the tank faces join the ray cast in any scene with "
                          "fluid when `tank_rays` is on.")
          .choice("method", &CouplingSpec::method, {"raytraced", "boundary_particles"},
                  "`raytraced`: each particle's motion is ray-cast against the bodies' surface "
                  "triangles and momentum is exchanged per face with the bodies' `restitution` "
                  "and `slip`. `boundary_particles`: the baseline, samples a particle spacing "
                  "apart on the body surfaces that move with them and push the fluid like the "
                  "tank's samples (Akinci et al. 2012); their forces return to the nodes. "
                  "Particles may then cross a surface; `crossed` counts them.")
          .number("skin", &CouplingSpec::skin, "-", Range().gt(0).lt(1),
                  "Distance kept between a particle and a surface it hits, as a fraction of "
                  "the particle radius.")
          .boolean("near_surface_density", &CouplingSpec::near_surface_density,
                   "Ray-traced coupling: add the kernel mass missing beyond a body's surface "
                   "(from the distance to the closest point), and its pressure force, so fluid "
                   "next to a body keeps its rest density; the force goes back to the face's "
                   "nodes. Closed obstacles (boxes, closed meshes) count as such surfaces too, "
                   "of infinite mass; open ones do not (fluid may lie on both sides).")
          .boolean("implicit_exchange", &CouplingSpec::implicit_exchange,
                   "Ray-traced coupling: the joint momentum exchange meets each body through "
                   "the operator of its implicit step, (1 + dt alpha) M + dt (dt + beta) K, so "
                   "a light node held by its elements is not taken for a free one, and the "
                   "nodes take the solve's velocity change at once. With "
                   "`near_surface_density`, the normal push of the near-surface pressure and "
                   "the particles within a radius of a face join the exchange too. "
                   "Experimental: it does not yet settle a light cloth under a water column "
                   "(docs/validation.md). `false`: free nodes of their lumped masses, as in "
                   "the paper.")
          .boolean("tank_rays", &CouplingSpec::tank_rays,
                   "Ray-cast the tank's six faces too, as static colliders of infinite mass, "
                   "so no particle ever crosses a wall.")
          .number("rebuild_quality", &CouplingSpec::rebuild_quality, "-", Range().gt(1),
                  "Rebuild a body's BVH (instead of refitting it) when its total box area "
                  "exceeds this multiple of the area right after the last build.")
          .number("wall_restitution", &CouplingSpec::wall_restitution, "-", kUnit,
                  "Restitution of the tank's faces when `tank_rays` is on.")
          .number("wall_slip", &CouplingSpec::wall_slip, "-", kUnit,
                  "Slip of the tank's faces when `tank_rays` is on.")
          .build();
  return t;
}

}  // namespace

const ObjectTable& scene_table() {
  static const ObjectTable t =
      Table<SceneSpec>("", "A scene file is one JSON object with these sections.")
          .string("name", &SceneSpec::name, "Title of the scene, shown in logs and outputs.")
          .object("simulation", &SceneSpec::simulation, simulation_table(),
                  "Time span and solver; see `simulation`.")
          .object("fluid", &SceneSpec::fluid, fluid_table(),
                  "Fluid material and sources; see `fluid`.")
          .array("bodies", &SceneSpec::bodies, body_table(), "Deformable bodies; see `bodies[]`.")
          .array("obstacles", &SceneSpec::obstacles, obstacle_table(),
                 "Obstacles, fixed or moving; see `obstacles[]`.")
          .object("fem", &SceneSpec::fem, fem_table(), "Solver settings of the bodies; see `fem`.")
          .object("coupling", &SceneSpec::coupling, coupling_table(),
                  "Fluid-body momentum exchange; see `coupling`.")
          .object("domain", &SceneSpec::domain, domain_table(), "The tank; see `domain`.")
          .object("output", &SceneSpec::output, output_table(), "Frame output; see `output`.")
          .array("gauges", &SceneSpec::gauges, gauge_table(), "Probes; see `gauges[]`.")
          .build();
  return t;
}

SceneSpec example_scene() {
  SceneSpec s;
  s.name = "dam break with inflow";
  s.simulation.duration = 2.0;
  s.simulation.solver = SolverKind::DFSPH;
  s.fluid.particle_radius = 0.005;
  s.fluid.viscosity = 1e-6;
  s.fluid.xsph = 0.1;
  s.fluid.blocks.push_back({Vec3d(0, 0, 0), Vec3d(0.2, 0.3, 0.1), Vec3d(0, 0, 0)});
  EmitterSpec e;
  e.position = Vec3d(0.6, 0.35, 0.05);
  e.direction = Vec3d(0, -1, 0);
  e.radius = 0.02;
  e.speed = 1.0;
  e.start = 0.5;
  e.end = 1.5;
  s.fluid.emitters.push_back(e);
  s.domain.lo = Vec3d(0, 0, 0);
  s.domain.hi = Vec3d(0.8, 0.4, 0.1);
  s.output.fps = 30;
  // A soft cup under the nozzle, its bottom pinned to the floor.
  BodySpec cup;
  cup.name = "cup";
  cup.shape = BodyShape::Cup;
  cup.position = Vec3d(0.6, 0, 0.05);
  cup.radius = 0.04;
  cup.inner_radius = 0.03;
  cup.height = 0.08;
  cup.thickness = 0.01;
  cup.resolution = 8;
  cup.material.density = 1100;
  cup.material.young = 2e5;
  cup.material.poisson = 0.45;
  cup.material.alpha = 1.0;
  cup.material.beta = 1e-3;
  cup.pinned.boxes.push_back({Vec3d(0.56, 0, 0.01), Vec3d(0.64, 0, 0.09)});
  cup.restitution = 0.2;
  cup.slip = 0.8;
  s.bodies.push_back(cup);
  s.fem.cg_tolerance = 1e-3;
  s.fem.cg_max_iterations = 200;
  s.fem.friction = 0.5;
  s.coupling.method = CouplingMethod::RayTraced;
  s.coupling.skin = 0.2;
  s.gauges.push_back({"p_bottom", GaugeKind::Pressure, Vec3d(0.1, 0.005, 0.05), ""});
  s.gauges.push_back({"h_wall", GaugeKind::Height, Vec3d(0.79, 0, 0.05), ""});
  s.gauges.push_back({"cup_rim", GaugeKind::Node, Vec3d(0.64, 0.08, 0.05), "cup"});
  return s;
}

}  // namespace sphfem::scene
