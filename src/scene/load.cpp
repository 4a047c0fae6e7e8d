// Scene files: reading, field-by-field parsing, cross-field validation and the format docs, all
// driven by the field table in scene/fields.cpp.
#include "sphfem/scene/load.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>

#include "scene/messages.h"
#include "sphfem/scene/bodies.h"
#include "sphfem/scene/fields.h"
#include "sphfem/sph/model.h"

namespace sphfem {
namespace {

using nlohmann::json;
using nlohmann::ordered_json;
using scene::Field;
using scene::FieldType;
using scene::format_number;
using scene::format_value;
using scene::ObjectTable;
using scene::Range;
using namespace scene_text;

// What a JSON value is, for "got ..." in type errors.
std::string describe(const json& v) {
  switch (v.type()) {
    case json::value_t::null:
      return "null";
    case json::value_t::boolean:
      return std::string("a boolean (") + (v.get<bool>() ? "true" : "false") + ")";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float:
      return "a number (" + format_value(v) + ")";
    case json::value_t::string: {
      std::string s = v.get<std::string>();
      if (s.size() > 40) s = s.substr(0, 37) + "...";
      return "a string (" + in_quotes(s) + ")";
    }
    case json::value_t::array:
      return "an array of " + std::to_string(v.size()) + (v.size() == 1 ? " element" : " elements");
    case json::value_t::object:
      return "an object";
    default:
      return "an unsupported value";
  }
}

std::string unit_suffix(const Field& f) {
  return f.unit.empty() || f.unit == "-" ? "" : " in " + f.unit;
}

// A value that satisfies the field's range, preferably its default, for "e.g." in hints.
std::string example(const Field& f) {
  if (f.type == FieldType::IntegerList) return num(f.range.lo ? f.range.lo->value : 0.0);
  if (!f.default_value.is_number()) return format_value(f.default_value);
  const Range& r = f.range;
  std::vector<double> candidates = {f.default_value.get<double>()};
  if (r.lo) candidates.insert(candidates.end(), {r.lo->value, r.lo->value + 1});
  if (r.lo && r.hi) candidates.push_back(0.5 * (r.lo->value + r.hi->value));
  candidates.insert(candidates.end(), {1.0, 0.0});
  for (double c : candidates)
    if (r.contains(c)) return num(c);
  return num(candidates.front());
}

std::string expected(const Field& f) {
  switch (f.type) {
    case FieldType::Number:
      return "a number" + unit_suffix(f);
    case FieldType::Integer:
      return "an integer" + unit_suffix(f);
    case FieldType::IntegerList:
      return "an array of integers [i, j, ...]";
    case FieldType::Bool:
      return "true or false";
    case FieldType::String:
      return "a string";
    case FieldType::Enum:
      return "one of " + in_quotes_list(f.choices);
    case FieldType::Vec3:
      return "an array of 3 numbers [x, y, z]" + unit_suffix(f);
    case FieldType::Object:
      return "an object {...}";
    case FieldType::ObjectArray:
      return "an array of objects [{...}, ...]";
  }
  return "a value";
}

std::string type_fix(const Field& f) {
  switch (f.type) {
    case FieldType::Number:
      return "write a number without quotes, e.g. " + example(f);
    case FieldType::Integer:
      return "write a whole number without quotes, e.g. " + example(f);
    case FieldType::IntegerList:
      return "write whole numbers in brackets, e.g. [0, 1], or [] for none";
    case FieldType::Bool:
      return "write true or false without quotes";
    case FieldType::String:
      return "write text in double quotes";
    case FieldType::Enum:
      return "write one of " + in_quotes_list(f.choices);
    case FieldType::Vec3:
      return "write three numbers, e.g. " + example(f);
    case FieldType::Object:
      return "write the section as an object, e.g. " + in_quotes(f.key) + ": {...}";
    case FieldType::ObjectArray:
      return "write a list of objects, e.g. " + in_quotes(f.key) + ": [{...}], or [] for none";
  }
  return "see docs/scene-format.md";
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Edit distance counting a swap of neighbours as one edit (typos like "visocsity").
std::size_t edit_distance(const std::string& a, const std::string& b) {
  const std::size_t m = a.size(), k = b.size();
  std::vector<std::vector<std::size_t>> d(m + 1, std::vector<std::size_t>(k + 1));
  for (std::size_t i = 0; i <= m; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= k; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= m; ++i) {
    for (std::size_t j = 1; j <= k; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[m][k];
}

// The allowed name nearest to a misspelt one, if any is plausibly meant.
std::optional<std::string> closest(const std::string& word, const std::vector<std::string>& names) {
  const std::string w = lower(word);
  std::optional<std::string> best;
  std::size_t best_d = SIZE_MAX;
  for (const std::string& name : names) {
    const std::string c = lower(name);
    std::size_t d = edit_distance(w, c);
    const bool contains = c.size() >= 3 && w.find(c) != std::string::npos;
    if (contains) d = std::min<std::size_t>(d, 1);
    const std::size_t limit = std::max<std::size_t>(2, c.size() / 3);
    if (d <= limit && d < c.size() && d < best_d) {
      best = name;
      best_d = d;
    }
  }
  return best;
}

// Checks a number against its field's type and range; shared by parsing and validation.
void check_number(const Field& f, double v, const std::string& at, const std::string& file) {
  if (!std::isfinite(v))
    fail(file, at, "must be a finite number (got " + num(v) + ")",
         "write an ordinary number" + unit_suffix(f) + ", e.g. " + example(f));
  Range r = f.range;
  if (f.type == FieldType::Integer || f.type == FieldType::IntegerList) {
    if (v != std::floor(v))
      fail(file, at, "expected an integer, got a number (" + num(v) + ")",
           "write a whole number, e.g. " + example(f));
    if (!r.lo) r = r.ge(INT_MIN);
    if (!r.hi) r = r.le(INT_MAX);
  }
  if (!r.contains(v))
    fail(file, at, "must be " + r.text() + " (got " + num(v) + ")",
         "set a value " + r.text() + unit_suffix(f) + ", e.g. " + example(f));
}

// Reads JSON into spec structs following the field table.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  void object(const ObjectTable& t, const json& j, void* owner, const std::string& at,
              std::size_t index) {
    // Unknown keys first: a misspelt key is the likeliest cause of any later surprise.
    for (auto it = j.begin(); it != j.end(); ++it)
      if (!t.find(it.key())) unknown(t, it.key(), at);
    for (const Field& f : t.fields) {
      auto it = j.find(f.key);
      if (it != j.end()) field(f, *it, owner, join(at, f.key));
    }
    if (t.finish) t.finish(owner, index);
  }

 private:
  [[noreturn]] void unknown(const ObjectTable& t, const std::string& key, const std::string& at) {
    const std::vector<std::string> keys = t.keys();
    std::optional<std::string> guess = closest(key, keys);
    fail(file_, join(at, key), "unknown field",
         guess ? "did you mean " + in_quotes(*guess) + "?"
               : "the fields allowed here are " + in_quotes_list(keys));
  }

  [[noreturn]] void wrong_type(const Field& f, const json& v, const std::string& at) {
    fail(file_, at, "expected " + expected(f) + ", got " + describe(v), type_fix(f));
  }

  void field(const Field& f, const json& v, void* owner, const std::string& at) {
    switch (f.type) {
      case FieldType::Number:
      case FieldType::Integer:
        if (!v.is_number()) wrong_type(f, v, at);
        check_number(f, v.get<double>(), at, file_);
        store(f, owner, json(v.get<double>()), at);
        return;
      case FieldType::IntegerList:
        if (!v.is_array()) wrong_type(f, v, at);
        for (std::size_t i = 0; i < v.size(); ++i) {
          if (!v[i].is_number())
            fail(file_, indexed(at, i), "expected an integer, got " + describe(v[i]), type_fix(f));
          check_number(f, v[i].get<double>(), indexed(at, i), file_);
        }
        store(f, owner, v, at);
        return;
      case FieldType::Bool:
        if (!v.is_boolean()) wrong_type(f, v, at);
        store(f, owner, v, at);
        return;
      case FieldType::String:
        if (!v.is_string()) wrong_type(f, v, at);
        store(f, owner, v, at);
        return;
      case FieldType::Enum:
        enumeration(f, v, owner, at);
        return;
      case FieldType::Vec3:
        vector3(f, v, owner, at);
        return;
      case FieldType::Object:
        if (!v.is_object()) wrong_type(f, v, at);
        object(*f.table, v, f.child(owner), at, 0);
        return;
      case FieldType::ObjectArray:
        if (!v.is_array()) wrong_type(f, v, at);
        f.resize(owner, v.size());
        for (std::size_t i = 0; i < v.size(); ++i) {
          const std::string item = indexed(at, i);
          if (!v[i].is_object())
            fail(file_, item, "expected an object {...}, got " + describe(v[i]),
                 "write each entry of " + f.key + " as an object in braces");
          object(*f.table, v[i], f.element(owner, i), item, i);
        }
        return;
    }
  }

  void enumeration(const Field& f, const json& v, void* owner, const std::string& at) {
    if (!v.is_string()) wrong_type(f, v, at);
    const std::string name = v.get<std::string>();
    if (std::find(f.choices.begin(), f.choices.end(), name) == f.choices.end()) {
      std::optional<std::string> guess = closest(name, f.choices);
      fail(file_, at, "unknown " + f.key + " " + in_quotes(name),
           guess ? "did you mean " + in_quotes(*guess) + "? the allowed names are " +
                       in_quotes_list(f.choices)
                 : "use one of " + in_quotes_list(f.choices));
    }
    store(f, owner, v, at);
  }

  void vector3(const Field& f, const json& v, void* owner, const std::string& at) {
    if (!v.is_array() || v.size() != 3) wrong_type(f, v, at);
    json values = json::array();
    for (std::size_t i = 0; i < 3; ++i) {
      const std::string item = indexed(at, i);
      if (!v[i].is_number())
        fail(file_, item, "expected a number" + unit_suffix(f) + ", got " + describe(v[i]),
             "write three numbers without quotes, e.g. " + example(f));
      const double x = v[i].get<double>();
      if (!std::isfinite(x))
        fail(file_, item, "must be a finite number (got " + num(x) + ")",
             "write three ordinary numbers, e.g. " + example(f));
      values.push_back(x);
    }
    store(f, owner, values, at);
  }

  void store(const Field& f, void* owner, const json& v, const std::string& at) {
    try {
      f.set(owner, v);
    } catch (const scene::FieldError& e) { fail(file_, at, e.what(), e.fix); }
  }

  std::string file_;
};

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

// The spec as JSON in table order; J is json (sorted keys) or ordered_json (for the docs).
template <class J>
J to_json(const ObjectTable& t, const void* owner) {
  void* mutable_owner = const_cast<void*>(owner);  // accessors are shared with the reader
  J out = J::object();
  for (const Field& f : t.fields) {
    if (f.type == FieldType::Object) {
      out[f.key] = to_json<J>(*f.table, f.child(mutable_owner));
    } else if (f.type == FieldType::ObjectArray) {
      J items = J::array();
      for (std::size_t i = 0; i < f.count(owner); ++i)
        items.push_back(to_json<J>(*f.table, f.element(mutable_owner, i)));
      out[f.key] = items;
    } else {
      out[f.key] = J(f.get(owner));
    }
  }
  return out;
}

std::string pad(int indent) { return std::string(static_cast<std::size_t>(indent), ' '); }

// Scene-file layout: one field per line, vectors and other scalar lists on one line.
void pretty(const ordered_json& v, int indent, std::string& out) {
  if (v.is_object() && !v.empty()) {
    out += "{\n";
    std::size_t i = 0;
    for (auto it = v.begin(); it != v.end(); ++it, ++i) {
      out += pad(indent + 2) + in_quotes(it.key()) + ": ";
      pretty(*it, indent + 2, out);
      out += i + 1 < v.size() ? ",\n" : "\n";
    }
    out += pad(indent) + "}";
  } else if (v.is_array() && std::any_of(v.begin(), v.end(),
                                         [](const ordered_json& e) { return e.is_structured(); })) {
    out += "[\n";
    for (std::size_t i = 0; i < v.size(); ++i) {
      out += pad(indent + 2);
      pretty(v[i], indent + 2, out);
      out += i + 1 < v.size() ? ",\n" : "\n";
    }
    out += pad(indent) + "]";
  } else {
    out += format_value(json::parse(v.dump()));
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

// "line L, column C" of a 1-based byte position as nlohmann reports it; one past the end is EOF.
std::string text_position(const std::string& text, std::size_t byte) {
  const std::size_t end = std::min<std::size_t>(std::max<std::size_t>(byte, 1), text.size() + 1);
  const std::size_t before = end - 1;
  const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(before), '\n');
  const std::size_t newline = before > 0 ? text.rfind('\n', before - 1) : std::string::npos;
  const std::size_t column = newline == std::string::npos ? end : end - newline - 1;
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

}  // namespace

SceneSpec parse_scene(const nlohmann::json& scene, const std::string& path) {
  if (!scene.is_object())
    fail(path, "", "expected a JSON object {...}, got " + describe(scene),
         "write the scene as an object, e.g. {\"fluid\": {\"blocks\": [...]}}");
  SceneSpec spec;
  Reader(path).object(scene::scene_table(), scene, &spec, "", 0);
  spec.path = path;
  return spec;
}

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

  check_bodies(s, path);

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

SceneSpec load_scene(const std::string& path) {
  namespace fs = std::filesystem;
  const std::string file = display_file(path);
  std::error_code ec;
  std::string check = "check the path (a relative path is taken from the current directory";
  const fs::path cwd = fs::current_path(ec);
  check += ec ? ")" : ", " + cwd.string() + ")";
  if (path.empty()) throw SceneError(file + ": no scene file given; pass the path of a .json file");

  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) throw SceneError(one_line(file + ": file not found; " + check));
  if (fs::is_directory(status))
    throw SceneError(one_line(file + ": is a directory, not a scene file; " + check));
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw SceneError(one_line(file + ": cannot open the file (" + std::strerror(errno) + "); " +
                              check + ", and that the file is readable"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad())
    throw SceneError(one_line(file + ": cannot read the file (" + std::strerror(errno) + "); " +
                              check + ", and that the file is readable"));

  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw SceneError(file + ": the file is empty; write the scene as a JSON object, e.g. " +
                     "{\"fluid\": {\"blocks\": [{\"min\": [0, 0, 0], \"max\": [0.5, 0.5, 0.5]}]}}");

  json scene;
  try {
    scene = json::parse(text, nullptr, true, /*ignore_comments=*/true);
  } catch (const json::parse_error& e) {
    std::string reason = e.what();
    const std::size_t colon = reason.find(": ", reason.find("parse error"));
    if (colon != std::string::npos) reason = reason.substr(colon + 2);
    std::replace(reason.begin(), reason.end(), ';', ',');
    throw SceneError(one_line(file + ": " + text_position(text, e.byte) +
                              ": invalid JSON: " + reason +
                              "; fix the syntax at that position (often a missing or extra comma, "
                              "quote or bracket just before it)"));
  } catch (const json::out_of_range& e) {
    // Numbers beyond the range of a double, such as 1e999; nlohmann names the token.
    std::string reason = e.what();
    const std::size_t bracket = reason.find("] ");
    if (bracket != std::string::npos) reason = reason.substr(bracket + 2);
    std::string where;
    const std::size_t q0 = reason.find('\''), q1 = reason.rfind('\'');
    if (q0 != std::string::npos && q1 > q0) {
      const std::size_t at = text.find(reason.substr(q0 + 1, q1 - q0 - 1));
      if (at != std::string::npos) where = text_position(text, at + 1) + ": ";
    }
    throw SceneError(one_line(file + ": " + where + "invalid JSON: " + reason +
                              "; write numbers within the range of a double"));
  }

  SceneSpec spec = parse_scene(scene, path);
  validate_scene(spec, path);
  return spec;
}

nlohmann::json scene_to_json(const SceneSpec& scene) {
  return to_json<json>(scene::scene_table(), &scene);
}

namespace {

const char* type_name(FieldType t) {
  switch (t) {
    case FieldType::Number:
      return "number";
    case FieldType::Integer:
      return "integer";
    case FieldType::IntegerList:
      return "array of integers";
    case FieldType::Bool:
      return "boolean";
    case FieldType::String:
      return "string";
    case FieldType::Enum:
      return "enum";
    case FieldType::Vec3:
      return "vec3";
    case FieldType::Object:
      return "object";
    case FieldType::ObjectArray:
      return "array of objects";
  }
  return "";
}

std::string cell(std::string s) {
  std::string out;
  for (char c : s) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

std::string code(const std::string& s) { return "`" + s + "`"; }

void markdown_section(const ObjectTable& t, std::ostringstream& md) {
  md << "## " << (t.name.empty() ? std::string("Top level") : code(t.name)) << "\n\n"
     << t.description << "\n\n"
     << "| Field | Type | Unit | Default | Range | Description |\n"
     << "|---|---|---|---|---|---|\n";
  for (const Field& f : t.fields) {
    std::string range;
    if (f.type == FieldType::Number || f.type == FieldType::Integer ||
        f.type == FieldType::IntegerList)
      range = f.range.text();
    if (f.type == FieldType::IntegerList && !range.empty()) range = "each " + range;
    if (f.type == FieldType::Enum) {
      for (std::size_t i = 0; i < f.choices.size(); ++i)
        range += (i ? ", " : "") + code(in_quotes(f.choices[i]));
    }
    if (!f.constraint.empty()) range += (range.empty() ? "" : "; ") + f.constraint;
    const std::string fallback =
        f.default_value.is_null() ? "" : code(format_value(f.default_value));
    md << "| " << code(f.key) << " | " << type_name(f.type) << " | " << f.unit << " | "
       << cell(fallback) << " | " << cell(range) << " | " << cell(f.description) << " |\n";
  }
  md << "\n";
  for (const Field& f : t.fields)
    if (f.table) markdown_section(*f.table, md);
}

}  // namespace

std::string scene_format_markdown() {
  std::ostringstream md;
  md << "# Scene file format\n\n"
     << "<!-- Generated from the field table in src/scene/fields.cpp by scene_format_markdown();\n"
     << "     do not edit. Regenerate with\n"
     << "     SPHFEM_UPDATE_DOCS=1 <build>/tests/sphfem_tests --gtest_filter='SceneDocs.*' -->\n\n"
     << "A scene is one JSON file, given to `sphfem` on the command line. A relative path is "
        "taken from the current directory.\n\n"
     << "- All quantities are in SI units (metres, seconds, kilograms); the Unit column names "
        "each one, and `-` marks a dimensionless number.\n"
     << "- Every section and every field is optional and takes the default shown. The scene "
        "must still contain something to simulate: at least one entry in `fluid.blocks`, "
        "`fluid.emitters` or `bodies`.\n"
     << "- Unknown keys are errors, so a misspelt field never falls back to its default "
        "silently; the message suggests the nearest allowed name.\n"
     << "- A `vec3` is an array of exactly three numbers `[x, y, z]`; y points up. Numbers "
        "must be finite, integers whole.\n"
     << "- Comments (`//` and `/* */`) are allowed.\n"
     << "- An error names the file, the JSON path of the field (`fluid.emitters[0].radius`), "
        "what is wrong and how to fix it, on one line.\n\n";

  markdown_section(scene::scene_table(), md);

  const std::string k = num(scene::kMinDomainSpacings);
  md << "## Checks across fields\n\n"
     << "After every field has been read, the scene as a whole must satisfy:\n\n"
     << "- `domain.min` < `domain.max` on every axis.\n"
     << "- With fluid, the domain is at least " << k
     << " particle spacings (2 * `particle_radius`) wide on every axis.\n"
     << "- `simulation.dt_min` <= `simulation.dt_max`.\n"
     << "- At least one block, emitter or body.\n"
     << "- Each block has `min` < `max`, lies inside the domain and is at least one particle "
        "spacing thick on every axis.\n"
     << "- Each emitter's nozzle (the disc of `radius` around `position`, perpendicular to "
        "`direction`) lies inside the domain, its `radius` is at least one particle spacing, "
        "`direction` is non-zero and `start` < `end`.\n"
     << "- Each gauge lies inside the domain (a height gauge in x and z only) and gauge names "
        "are unique; a node gauge names a body, other gauges none; no two gauges.csv columns "
        "the scene names (`<gauge>`, `<gauge>_dx`, `<body>_kinetic_energy`, ...) are equal.\n"
     << "- Body names are unique. Box edges are positive (a cloth's on x and z); a tube's or "
        "cup's `inner_radius` is below its `radius`, a cup's bottom `thickness` below its "
        "`height`; a cup has at least 4 cells across, a sphere 2; a shape makes at most "
     << scene::kMaxBodyTets << " tetrahedra.\n"
     << "- A mesh body names a `file` that reads as a closed, manifold, consistently oriented "
        "surface without self-intersections (tetrahedralised with `max_volume` and "
        "`quality`), or as a tetrahedral mesh without inverted elements.\n"
     << "- Every body lies inside the domain; each pinned box holds at least one of its rest "
        "nodes and each pinned index is below its node count.\n"
     << "- The solver adds its own checks, such as the time step against the CFL condition.\n\n";

  const SceneSpec sample = scene::example_scene();
  std::string example;
  pretty(to_json<ordered_json>(scene::scene_table(), &sample), 0, example);
  md << "## Example\n\n"
     << "A scene that sets every field:\n\n"
     << "```json\n"
     << example << "\n"
     << "```\n";
  return md.str();
}

}  // namespace sphfem
