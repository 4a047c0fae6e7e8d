// A field's number check and the hint pieces built from a field (scene/field_checks.h).
#include "scene/field_checks.h"

#include <climits>
#include <cmath>
#include <vector>

#include "scene/messages.h"

namespace sphfem::scene {

using namespace scene_text;

std::string unit_suffix(const Field& f) {
  return f.unit.empty() || f.unit == "-" ? "" : " in " + f.unit;
}

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

}  // namespace sphfem::scene
