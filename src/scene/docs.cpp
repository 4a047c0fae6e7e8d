// The format docs: docs/scene-format.md generated from the field table (scene_format_markdown).
#include <sstream>
#include <string>

#include "scene/messages.h"
#include "scene/write.h"
#include "sphfem/scene/fields.h"
#include "sphfem/scene/limits.h"
#include "sphfem/scene/load.h"

namespace sphfem {
namespace {

using nlohmann::ordered_json;
using scene::Field;
using scene::FieldType;
using scene::format_value;
using scene::ObjectTable;
using scene::pretty;
using scene::to_json;
using namespace scene_text;

// 200000000 as "200,000,000".
std::string count_text(double n) {
  std::string digits = std::to_string(static_cast<long long>(n)), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

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

  // The caps of scene/limits.h, checked from the fields before anything is allocated.
  md << "## Limits\n\n"
     << "Before anything is built, the loader counts what the scene would need from its fields "
        "alone and refuses, naming the field that drives the count, a scene that passes a cap "
        "(`sphfem check` prints the counts of a scene that fits):\n\n"
     << "- at most " << count_text(kMaxParticles)
     << " fluid particles, those the emitters add over the run and `fluid.max_particles` "
        "included;\n"
     << "- at most " << count_text(kMaxWallSamples) << " samples in the tank's walls and "
     << count_text(kMaxGridCells) << " cells in the neighbour grid (cell size 4 * "
     << "`particle_radius` over the domain and its walls);\n"
     << "- at most " << count_text(kMaxFrames)
     << " frames in a run (`simulation.duration` * `output.fps` + 1, also for `run "
        "--duration`);\n"
     << "- at most " << scene::kMaxBodyTets
     << " tetrahedra per body: a shape's `resolution`, and a mesh file's `max_volume` (the "
        "surface's volume / `max_volume` is fewer tetrahedra than TetGen makes);\n"
     << "- and the memory all of it needs at most the memory free on the machine "
        "(`MemAvailable`, or a container's `memory.max` when lower): about 426 B per particle "
        "(264 B of it the neighbour list, 48 B the initial state kept), 185 B more per "
        "particle with the ray coupling's rays (225 B with obstacles) and 220 B per contact "
        "against the tank's faces, 88 B per wall sample, 8 B per grid cell and 1 MiB of "
        "tables; 281 B per body node, 372 B per tetrahedron and 36 B per surface triangle "
        "(counted as two a node before meshing), with `fem.contact` 105 B, 57 B and 216 B more, "
        "with fluid 16 B a node and 80 B a triangle more, with `fem.preconditioner` "
        "`two_level` 17 B a node and its sparse matrix and factor, bounded by 16 B times the "
        "square of 6 unknowns per 16 nodes, at most 52 MB (the bench's bunny holds 4 MB). For "
        "fluid with the tank's faces in "
        "the rays, and for bodies alone, with contact or in water, this comes to 1.0-1.25 "
        "times what a run holds (`tests/scene_limits_test.cpp`).\n\n";

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
