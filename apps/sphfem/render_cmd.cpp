#include "render_cmd.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "sphfem/io/atomic_file.h"
#include "sphfem/io/vtu.h"
#include "sphfem/io/xml.h"
#include "sphfem/render/camera.h"
#include "sphfem/render/splat.h"

namespace {

using namespace sphfem;
namespace fs = std::filesystem;

struct FrameRef {
  std::string file;  // relative to the run folder
  long number;       // NNNNNN of fluid_NNNNNN, or the position in the list
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

long frame_number(const std::string& file, long fallback) {
  const std::string stem = fs::path(file).stem().string();
  const std::size_t us = stem.find_last_of('_');
  const std::string digits = us == std::string::npos ? stem : stem.substr(us + 1);
  if (digits.empty() || digits.size() > 9 ||
      !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return fallback;
  return std::stol(digits);
}

// The DataSet entries of a collection written by io::PvdCollection, in file order.
std::vector<FrameRef> read_pvd(const std::string& path) {
  const std::string text = slurp(path);
  std::vector<FrameRef> frames;
  for (std::size_t at = text.find("<DataSet"); at != std::string::npos;
       at = text.find("<DataSet", at + 1)) {
    const std::size_t end = text.find('>', at);
    if (end == std::string::npos) break;
    const auto attrs = io::xml_attributes(text.substr(at + 1, end - at - 1));
    const auto file = attrs.find("file");
    if (file == attrs.end() || file->second.empty()) continue;
    frames.push_back({file->second, frame_number(file->second, long(frames.size()))});
  }
  return frames;
}

std::vector<FrameRef> select_frames(const std::vector<FrameRef>& all, const std::string& which,
                                    const std::string& pvd) {
  if (which == "all") return all;
  if (which == "last") return {all.back()};
  char* end = nullptr;
  const long n = std::strtol(which.c_str(), &end, 10);
  if (which.empty() || *end != '\0' || n < 0)
    throw std::runtime_error("--frames '" + which +
                             "' is not understood: give all, last or a frame number such as 0");
  for (const FrameRef& f : all)
    if (f.number == n) return {f};
  throw std::runtime_error("frame " + which + " is not in '" + pvd + "' (it lists frames " +
                           std::to_string(all.front().number) + " to " +
                           std::to_string(all.back().number) + "); pick one of those");
}

struct Tank {
  double radius = 0;
  Vec3d lo, hi;
  bool known = false;
};

Tank read_run_info(const std::string& path) {
  Tank t;
  if (!fs::exists(path)) return t;
  try {
    const nlohmann::json j = nlohmann::json::parse(slurp(path));
    t.radius = j.at("particle_radius").get<double>();
    const auto& lo = j.at("domain").at("min");
    const auto& hi = j.at("domain").at("max");
    t.lo = Vec3d(lo.at(0).get<double>(), lo.at(1).get<double>(), lo.at(2).get<double>());
    t.hi = Vec3d(hi.at(0).get<double>(), hi.at(1).get<double>(), hi.at(2).get<double>());
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("'" + path + "' is not a run description (" + e.what() +
                             "); run the scene again or delete the file to guess from the frames");
  }
  if (!(t.radius > 0))
    throw std::runtime_error("'" + path + "' gives particle_radius <= 0; run the scene again");
  t.known = true;
  return t;
}

// Half the median distance to the nearest other particle, over an even sample of particles.
double estimate_radius(const std::vector<float>& x) {
  const std::size_t n = x.size() / 3;
  if (n < 2) return 0.01;
  const std::size_t stride = std::max<std::size_t>(1, n / 400);
  std::vector<double> nearest;
  for (std::size_t i = 0; i < n; i += stride) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < n; ++k) {
      if (k == i) continue;
      const double dx = x[3 * k] - x[3 * i], dy = x[3 * k + 1] - x[3 * i + 1],
                   dz = x[3 * k + 2] - x[3 * i + 2];
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (d2 > 0) best = std::min(best, d2);
    }
    if (std::isfinite(best)) nearest.push_back(std::sqrt(best));
  }
  if (nearest.empty()) return 0.01;
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  return 0.5 * nearest[nearest.size() / 2];
}

const io::DataArray* find_array(const io::PointSet& ps, const std::string& name) {
  for (const auto& a : ps.point_data)
    if (a.name == name) return &a;
  return nullptr;
}

}  // namespace

int run_render(const RenderOptions& opt) {
  const std::string dir = opt.out_dir.empty() ? "." : opt.out_dir;
  if (!fs::is_directory(dir))
    throw std::runtime_error("run folder '" + dir +
                             "' does not exist; make it with `sphfem run SCENE --out " + dir + "`");
  const std::string pvd = dir + "/fluid.pvd";
  if (!fs::exists(pvd))
    throw std::runtime_error("'" + pvd +
                             "' not found: the run wrote no VTU frames; run the scene with "
                             "\"output\": {\"vtu\": true} (the default)");
  const std::vector<FrameRef> all = read_pvd(pvd);
  if (all.empty())
    throw std::runtime_error("'" + pvd + "' lists no frames; let the run write at least one");
  if (opt.width <= 0 || opt.height <= 0 || opt.width > 16384 || opt.height > 16384)
    throw std::runtime_error("image size " + std::to_string(opt.width) + "x" +
                             std::to_string(opt.height) + " is out of range; use 1 to 16384");
  const std::vector<FrameRef> frames = select_frames(all, opt.frames, pvd);

  Tank tank = read_run_info(dir + "/run.json");
  const std::string images = dir + "/images";
  io::ensure_directory(images);
  render::Camera cam;
  for (const FrameRef& f : frames) {
    const io::PointSet ps = io::read_vtu_points(dir + "/" + f.file);
    if (!tank.known) {
      // An older run without run.json: guess once, from the first frame, so the camera
      // stays put for the rest.
      tank.radius = estimate_radius(ps.positions);
      tank.lo = Vec3d(1e300, 1e300, 1e300);
      tank.hi = -tank.lo;
      for (std::size_t i = 0; i < ps.size(); ++i) {
        const Vec3d p(ps.positions[3 * i], ps.positions[3 * i + 1], ps.positions[3 * i + 2]);
        if (!std::isfinite(p.x + p.y + p.z)) continue;
        tank.lo = vmin(tank.lo, p);
        tank.hi = vmax(tank.hi, p);
      }
      if (tank.lo.x > tank.hi.x) tank.lo = tank.hi = Vec3d();  // no finite particle
      const Vec3d pad(tank.radius, tank.radius, tank.radius);
      tank.lo = tank.lo - pad;
      tank.hi = tank.hi + pad;
      std::fprintf(stderr,
                   "%s/run.json not found: guessed particle radius %.4g m and the particles' "
                   "bounding box as the tank\n",
                   dir.c_str(), tank.radius);
      tank.known = true;
    }
    if (&f == &frames.front()) cam = render::auto_frame(tank.lo, tank.hi, opt.width, opt.height);

    std::vector<float> speed;
    const io::DataArray* vel = find_array(ps, "velocity");
    if (vel && !vel->is_int() && vel->components == 3 && vel->values.size() == 3 * ps.size()) {
      speed.resize(ps.size());
      for (std::size_t i = 0; i < ps.size(); ++i)
        speed[i] = std::sqrt(vel->values[3 * i] * vel->values[3 * i] +
                             vel->values[3 * i + 1] * vel->values[3 * i + 1] +
                             vel->values[3 * i + 2] * vel->values[3 * i + 2]);
    }
    const render::Image img = render::render_particles(
        cam, ps.positions, speed.empty() ? nullptr : &speed, float(tank.radius), tank.lo, tank.hi);
    const std::string out = images + "/" + fs::path(f.file).stem().string() + ".png";
    render::write_png(out, img);
    std::printf("%s\n", out.c_str());
    std::fflush(stdout);
  }
  std::printf("%zu image%s in %s\n", frames.size(), frames.size() == 1 ? "" : "s", images.c_str());
  return 0;
}
