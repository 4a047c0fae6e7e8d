// A field's number check and the pieces of hints built from a field (its unit, an example
// value), shared by parsing (parse.cpp) and validation (validate.cpp).
#pragma once

#include <string>

#include "sphfem/scene/fields.h"

namespace sphfem::scene {

// " in <unit>" for messages, or "" for a dimensionless field.
std::string unit_suffix(const Field& f);

// A value that satisfies the field's range, preferably its default, for "e.g." in hints.
std::string example(const Field& f);

// Checks a number against its field's type and range; throws SceneError naming `file` and `at`.
void check_number(const Field& f, double v, const std::string& at, const std::string& file);

}  // namespace sphfem::scene
