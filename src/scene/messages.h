// Pieces of scene error messages, shared by the loader and the body checks so that every
// message has the same form: "<file>: <json.path>: <what is wrong>; <how to fix it>".
#pragma once

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sphfem/core/vec.h"
#include "sphfem/scene/fields.h"
#include "sphfem/scene/load.h"

namespace sphfem::scene_text {

inline const char* const kAxis[3] = {"x", "y", "z"};

// Messages must stay on one line whatever the input contained.
inline std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  return s;
}

inline std::string display_file(const std::string& path) { return path.empty() ? "(scene)" : path; }
inline std::string display_at(const std::string& at) { return at.empty() ? "(top level)" : at; }

[[noreturn]] inline void fail(const std::string& file, const std::string& at,
                              const std::string& what, const std::string& fix) {
  throw SceneError(one_line(display_file(file) + ": " + display_at(at) + ": " + what + "; " + fix));
}

inline std::string join(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

inline std::string indexed(const std::string& at, std::size_t i) {
  return at + "[" + std::to_string(i) + "]";
}

inline std::string in_quotes(const std::string& s) {
  return nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

inline std::string in_quotes_list(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i) s += (i ? ", " : "") + in_quotes(names[i]);
  return s;
}

// The file as the scene means it: a relative path starts at the scene file's folder.
inline std::string resolve_path(const std::string& file, const std::string& scene_file) {
  namespace fs = std::filesystem;
  const fs::path p(file);
  if (p.is_absolute() || scene_file.empty()) return file;
  return (fs::path(scene_file).parent_path() / p).lexically_normal().string();
}

inline std::string num(double v) { return scene::format_number(v); }
inline std::string vec(const Vec3d& v) {
  return "[" + num(v.x) + ", " + num(v.y) + ", " + num(v.z) + "]";
}

}  // namespace sphfem::scene_text
