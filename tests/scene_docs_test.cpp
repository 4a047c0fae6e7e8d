// docs/scene-format.md is generated from the field table; this keeps the two identical.
// SPHFEM_UPDATE_DOCS=1 makes the test rewrite the file instead of comparing.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "sphfem/scene/fields.h"
#include "sphfem/scene/load.h"

namespace sphfem {
namespace {

using scene::Field;
using scene::FieldType;
using scene::ObjectTable;

TEST(SceneDocs, FormatDocMatchesTheFieldTable) {
  const std::string path = std::string(SPHFEM_SOURCE_DIR) + "/docs/scene-format.md";
  const std::string generated = scene_format_markdown();
  const char* update = std::getenv("SPHFEM_UPDATE_DOCS");
  if (update && std::string(update) == "1") {
    std::ofstream(path, std::ios::binary) << generated;
    SUCCEED() << "wrote " << path;
    return;
  }
  std::ifstream in(path, std::ios::binary);
  std::ostringstream committed;
  committed << in.rdbuf();
  if (committed.str() == generated) return;
  // Point at the first line that differs; the whole text would drown the hint.
  std::istringstream a(committed.str()), b(generated);
  std::string line_a, line_b;
  int line = 0;
  while (true) {
    ++line;
    const bool more_a = static_cast<bool>(std::getline(a, line_a));
    const bool more_b = static_cast<bool>(std::getline(b, line_b));
    if (line_a != line_b || more_a != more_b || (!more_a && !more_b)) break;
  }
  ADD_FAILURE() << "docs/scene-format.md is out of date with the field table "
                   "(src/scene/fields.cpp); first difference at line "
                << line << ":\n  committed: " << line_a << "\n  generated: " << line_b
                << "\nRegenerate it with: SPHFEM_UPDATE_DOCS=1 <build>/tests/sphfem_tests "
                   "--gtest_filter='SceneDocs.*'";
}

// Walks every field of the format, with its JSON path.
template <class Fn>
void for_each_field(const ObjectTable& t, const std::string& at, Fn fn) {
  for (const Field& f : t.fields) {
    const std::string here = at.empty() ? f.key : at + "." + f.key;
    fn(f, here);
    if (f.table)
      for_each_field(*f.table, here + (f.type == FieldType::ObjectArray ? "[]" : ""), fn);
  }
}

TEST(SceneDocs, EveryFieldIsFullyDeclared) {
  for_each_field(scene::scene_table(), "", [](const Field& f, const std::string& at) {
    EXPECT_FALSE(f.description.empty()) << at;
    const bool numeric =
        f.type == FieldType::Number || f.type == FieldType::Integer || f.type == FieldType::Vec3;
    EXPECT_EQ(numeric, !f.unit.empty()) << at << ": numbers need a unit, others none";
    if (f.type == FieldType::Enum) { EXPECT_FALSE(f.choices.empty()) << at; }
    if (f.is_scalar()) { EXPECT_TRUE(f.get && f.set) << at; }
  });
}

TEST(SceneDocs, EveryDefaultIsInsideItsRange) {
  for_each_field(scene::scene_table(), "", [](const Field& f, const std::string& at) {
    if (f.type == FieldType::Number || f.type == FieldType::Integer) {
      EXPECT_TRUE(f.range.contains(f.default_value.get<double>()))
          << at << " default " << f.default_value << " is not " << f.range.text();
    }
  });
}

TEST(SceneDocs, ExampleSceneIsValid) {
  EXPECT_NO_THROW(validate_scene(scene::example_scene(), "example"));
}

}  // namespace
}  // namespace sphfem
