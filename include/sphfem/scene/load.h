// Reading, checking and documenting scene files; the format is docs/scene-format.md, generated
// from the field table in scene/fields.h.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <stdexcept>
#include <string>

#include "sphfem/scene/spec.h"

namespace sphfem {

// A scene that cannot be used. what() is one line:
// "<file>: <json.path>: <what is wrong>; <how to fix it>".
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Reads, parses and validates a scene file; a relative path is taken from the current directory.
SceneSpec load_scene(const std::string& path);

// Fills a SceneSpec from parsed JSON, checking keys, types and ranges field by field.
// `path` is only used to name the file in messages.
SceneSpec parse_scene(const nlohmann::json& scene, const std::string& path);

// Cross-field checks (geometry, time steps, fluid present) on a parsed or hand-built scene.
void validate_scene(const SceneSpec& scene, const std::string& path);

// The scene as a scene-file JSON object with every field written; parse_scene reads it back.
nlohmann::json scene_to_json(const SceneSpec& scene);

// The complete text of docs/scene-format.md.
std::string scene_format_markdown();

}  // namespace sphfem
