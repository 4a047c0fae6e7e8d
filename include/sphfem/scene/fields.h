// The scene-file format as data: every JSON field declared once, with its key, type, unit,
// default, allowed range and description. This one table drives loading, the validation
// messages and docs/scene-format.md (scene/load.h).
#pragma once

#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sphfem/scene/spec.h"

namespace sphfem::scene {

enum class FieldType {
  Number,
  Integer,
  IntegerList,
  Bool,
  String,
  Enum,
  Vec3,
  Object,
  ObjectArray
};

// One end of a numeric range.
struct Bound {
  double value = 0.0;
  bool inclusive = true;
};

// Values a number may take; a missing bound leaves that side open.
struct Range {
  std::optional<Bound> lo, hi;

  Range gt(double v) const { return with_lo(v, false); }
  Range ge(double v) const { return with_lo(v, true); }
  Range lt(double v) const { return with_hi(v, false); }
  Range le(double v) const { return with_hi(v, true); }

  bool contains(double v) const;
  // Reads after "must be", e.g. "> 0" or ">= 0 and <= 1"; empty when unbounded.
  std::string text() const;

 private:
  Range with_lo(double v, bool inclusive) const;
  Range with_hi(double v, bool inclusive) const;
};

// A well-typed value that is still unusable, thrown by a field's setter; the loader adds the
// file name and JSON path.
struct FieldError : std::runtime_error {
  FieldError(const std::string& problem, std::string fix_hint)
      : std::runtime_error(problem), fix(std::move(fix_hint)) {}
  std::string fix;
};

struct ObjectTable;

// One JSON key. Accessors take the owning struct as void* so that tables of different structs
// share one type; the owner's type is fixed by the table the field belongs to.
struct Field {
  std::string key;
  FieldType type = FieldType::Number;
  std::string unit;                    // SI unit; "-" when dimensionless, "" for non-numbers
  Range range;                         // Number, Integer and each IntegerList element
  std::vector<std::string> choices;    // Enum: names in enumerator order
  std::string constraint;              // rule beyond the type and range, e.g. "non-zero"
  std::string description;             // one sentence
  const ObjectTable* table = nullptr;  // Object and ObjectArray: the nested declaration
  nlohmann::json default_value;        // read from a default-constructed owner

  // Scalars (all but Object and ObjectArray): member as JSON, and store a checked value.
  std::function<nlohmann::json(const void* owner)> get;
  std::function<void(void* owner, const nlohmann::json& value)> set;
  // Object: the nested struct.
  std::function<void*(void* owner)> child;
  // ObjectArray: the vector's size, resizing it, and element i.
  std::function<std::size_t(const void* owner)> count;
  std::function<void(void* owner, std::size_t n)> resize;
  std::function<void*(void* owner, std::size_t i)> element;

  bool is_scalar() const { return type != FieldType::Object && type != FieldType::ObjectArray; }
};

// The fields of one JSON object (one spec struct).
struct ObjectTable {
  std::string name;         // JSON path of the object, "fluid.emitters[]"; "" at the top level
  std::string description;  // one sentence for the docs
  std::vector<Field> fields;
  // Runs after an object's fields are read, for values that depend on its position in a list.
  std::function<void(void* object, std::size_t index)> finish;

  const Field* find(const std::string& key) const;
  std::vector<std::string> keys() const;
};

// Root of the format; its owner type is SceneSpec.
const ObjectTable& scene_table();

// A complete, valid scene that sets every field; the docs print it as the example.
SceneSpec example_scene();

// Cross-field limits, shared by validate_scene and the docs that describe it.
inline constexpr double kMinDomainSpacings = 4.0;  // domain width in particle spacings, per axis
inline constexpr double kMinTetgenQuality = 1.1;   // TetGen may not finish below this ratio
inline constexpr long kMaxBodyTets = 5000000;      // tetrahedra per generated body

// Shortest text that reads back as the same double: 0.4, 1e-06, 1000.
std::string format_number(double v);
// A JSON value as it would be written in a scene file, on one line with short numbers.
std::string format_value(const nlohmann::json& v);

}  // namespace sphfem::scene
