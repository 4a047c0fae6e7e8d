// run.json written and read in one place, so the runner and the renderer cannot drift apart.
#include "sphfem/io/run_info.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "sphfem/io/atomic_file.h"

namespace sphfem::io {
namespace fs = std::filesystem;
using nlohmann::json;

std::string run_json_path(const std::string& dir) { return (fs::path(dir) / "run.json").string(); }
std::string frames_dir(const std::string& dir) { return (fs::path(dir) / "frames").string(); }
std::string gauges_path(const std::string& dir) { return (fs::path(dir) / "gauges.csv").string(); }
std::string checkpoint_path(const std::string& dir) {
  return (fs::path(dir) / "checkpoint.bin").string();
}

namespace {

json to_json(const Vec3d& v) { return json::array({v.x, v.y, v.z}); }

// One field of one file: every complaint names both and says how to get a good file back.
class Reader {
 public:
  explicit Reader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw std::runtime_error("'" + path_ + "' is not a run description (" + field + ": " + what +
                             "); run the scene again or delete the file to guess from the frames");
  }

  // The value as written, cut short: enough to recognise it in the file.
  static std::string shown(const json& j) {
    std::string s = j.dump();
    return s.size() > 40 ? s.substr(0, 37) + "..." : s;
  }

  const json& need(const json& obj, const char* key, const std::string& field) const {
    if (!obj.contains(key)) fail(field, "missing");
    return obj.at(key);
  }

  double number(const json& j, const std::string& field) const {
    if (!j.is_number()) fail(field, "expected a number, got " + shown(j));
    return j.get<double>();
  }

  std::string text(const json& j, const std::string& field) const {
    if (!j.is_string()) fail(field, "expected a string, got " + shown(j));
    return j.get<std::string>();
  }

  Vec3d vec3(const json& j, const std::string& field) const {
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() ||
        !j[2].is_number())
      fail(field, "expected three numbers [x, y, z], got " + shown(j));
    return Vec3d(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
  }

  const json& object(const json& j, const std::string& field) const {
    if (!j.is_object()) fail(field, "expected an object {...}, got " + shown(j));
    return j;
  }

 private:
  std::string path_;
};

}  // namespace

void write_run_info(const std::string& dir, const RunInfo& info) {
  json bodies = json::array();
  for (const std::string& b : info.bodies) bodies.push_back(b);
  json j = {{"scene", info.scene},
            {"name", info.name},
            {"particle_radius", info.particle_radius},
            {"domain", {{"min", to_json(info.domain_min)}, {"max", to_json(info.domain_max)}}},
            {"solver", info.solver},
            {"backend", info.backend},
            {"fps", info.fps},
            {"bodies", bodies}};
  if (info.camera) {
    json c = json::object();
    if (info.camera->position) c["position"] = to_json(*info.camera->position);
    if (info.camera->target) c["target"] = to_json(*info.camera->target);
    if (info.camera->fov > 0) c["fov"] = info.camera->fov;
    j["camera"] = c;
  }
  write_file_atomic(run_json_path(dir), j.dump(2) + "\n");
}

bool run_info_exists(const std::string& dir) {
  std::error_code ec;
  return fs::exists(run_json_path(dir), ec);
}

RunInfo read_run_info(const std::string& dir) {
  const std::string path = run_json_path(dir);
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw std::runtime_error("'" + path +
                             "' not found; run the scene with `sphfem run SCENE --out " + dir +
                             "` to write it");
  if (fs::is_directory(path, ec))
    throw std::runtime_error("'" + path + "' is a folder, not a run description; remove it");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error("cannot read '" + path + "': " + std::strerror(errno) +
                             "; check its permissions");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());

  const Reader r(path);
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) { r.fail("JSON", e.what()); }
  r.object(j, "top level");

  RunInfo info;
  info.particle_radius =
      r.number(r.need(j, "particle_radius", "particle_radius"), "particle_radius");
  const json& domain = r.object(r.need(j, "domain", "domain"), "domain");
  info.domain_min = r.vec3(r.need(domain, "min", "domain.min"), "domain.min");
  info.domain_max = r.vec3(r.need(domain, "max", "domain.max"), "domain.max");
  // The rest describe the run; older runs may lack them.
  if (j.contains("scene")) info.scene = r.text(j.at("scene"), "scene");
  if (j.contains("name")) info.name = r.text(j.at("name"), "name");
  if (j.contains("solver")) info.solver = r.text(j.at("solver"), "solver");
  if (j.contains("backend")) info.backend = r.text(j.at("backend"), "backend");
  if (j.contains("fps")) info.fps = r.number(j.at("fps"), "fps");
  if (j.contains("bodies")) {
    const json& b = j.at("bodies");
    if (!b.is_array()) r.fail("bodies", "expected a list of names, got " + Reader::shown(b));
    for (std::size_t i = 0; i < b.size(); ++i)
      info.bodies.push_back(r.text(b[i], "bodies[" + std::to_string(i) + "]"));
  }
  if (j.contains("camera")) {
    const json& c = r.object(j.at("camera"), "camera");
    RunCamera cam;
    if (c.contains("position")) cam.position = r.vec3(c.at("position"), "camera.position");
    if (c.contains("target")) cam.target = r.vec3(c.at("target"), "camera.target");
    if (c.contains("fov")) cam.fov = r.number(c.at("fov"), "camera.fov");
    info.camera = cam;
  }
  if (!(info.particle_radius > 0))
    throw std::runtime_error("'" + path + "' gives particle_radius <= 0; run the scene again");
  return info;
}

}  // namespace sphfem::io
