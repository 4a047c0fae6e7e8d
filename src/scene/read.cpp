// Reading a scene file: the file itself, JSON with comments, syntax errors as text positions;
// then parse_scene (parse.cpp) and validate_scene (validate.cpp).
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "scene/messages.h"
#include "sphfem/scene/load.h"

namespace sphfem {
namespace {

using nlohmann::json;
using namespace scene_text;

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

}  // namespace sphfem
