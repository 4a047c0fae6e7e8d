#include "render_cmd.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include "bench.h"
#include "sphfem/io/atomic_file.h"
#include "sphfem/io/ply.h"
#include "sphfem/io/run_info.h"
#include "sphfem/io/vtu.h"
#include "sphfem/io/xml.h"
#include "sphfem/render/camera.h"
#include "sphfem/render/frame_io.h"
#include "sphfem/render/headless.h"
#include "sphfem/render/splat.h"

namespace {

using namespace sphfem;
namespace fs = std::filesystem;

// The files of one output frame, relative to the run folder; either may be empty.
struct FrameFiles {
  long number = 0;
  std::string fluid, bodies, obstacles;
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

// The DataSet files of a collection written by io::PvdCollection, in file order.
std::vector<std::string> read_pvd(const std::string& path) {
  const std::string text = slurp(path);
  std::vector<std::string> files;
  for (std::size_t at = text.find("<DataSet"); at != std::string::npos;
       at = text.find("<DataSet", at + 1)) {
    const std::size_t end = text.find('>', at);
    if (end == std::string::npos) break;
    const auto attrs = io::xml_attributes(text.substr(at + 1, end - at - 1));
    const auto file = attrs.find("file");
    if (file != attrs.end() && !file->second.empty()) files.push_back(file->second);
  }
  return files;
}

// Frames by number. The collections name the latest run's frames (a reused folder may hold
// older ones); a run that wrote PLY only has no collection, so its frames/ folder is listed.
std::vector<FrameFiles> list_frames(const std::string& dir) {
  std::map<long, FrameFiles> frames;
  auto add = [&](const std::string& file, std::string FrameFiles::*kind, long fallback) {
    const long n = frame_number(file, fallback);
    FrameFiles& f = frames[n];
    f.number = n;
    f.*kind = file;
  };
  const bool fluid_pvd = fs::exists(dir + "/fluid.pvd");
  if (fluid_pvd) {
    const auto files = read_pvd(dir + "/fluid.pvd");
    for (std::size_t i = 0; i < files.size(); ++i) add(files[i], &FrameFiles::fluid, long(i));
  }
  if (fs::exists(dir + "/bodies.pvd")) {
    const auto files = read_pvd(dir + "/bodies.pvd");
    for (std::size_t i = 0; i < files.size(); ++i) add(files[i], &FrameFiles::bodies, long(i));
  }
  // Obstacles on a path have a file per frame; only frames with fluid or bodies are listed.
  if (!frames.empty() && fs::exists(dir + "/obstacles.pvd")) {
    const auto files = read_pvd(dir + "/obstacles.pvd");
    for (std::size_t i = 0; i < files.size(); ++i) {
      const auto it = frames.find(frame_number(files[i], long(i)));
      if (it != frames.end()) it->second.obstacles = files[i];
    }
  }
  if (!fluid_pvd && fs::is_directory(io::frames_dir(dir))) {
    std::vector<std::string> ply;
    for (const auto& e : fs::directory_iterator(io::frames_dir(dir))) {
      const std::string name = e.path().filename().string();
      if (name.rfind("fluid_", 0) == 0 && e.path().extension() == ".ply" &&
          frame_number(name, -1) >= 0)
        ply.push_back("frames/" + name);
    }
    std::sort(ply.begin(), ply.end());
    for (const std::string& f : ply) add(f, &FrameFiles::fluid, 0);
  }
  std::vector<FrameFiles> out;
  for (auto& [n, f] : frames) out.push_back(f);
  return out;
}

std::vector<FrameFiles> select_frames(const std::vector<FrameFiles>& all, const std::string& which,
                                      const std::string& dir) {
  if (which == "all") return all;
  if (which == "last") return {all.back()};
  char* end = nullptr;
  const long n = std::strtol(which.c_str(), &end, 10);
  if (which.empty() || *end != '\0' || n < 0)
    throw std::runtime_error("--frames '" + which +
                             "' is not understood: give all, last or a frame number such as 0");
  for (const FrameFiles& f : all)
    if (f.number == n) return {f};
  throw std::runtime_error("frame " + which + " is not in '" + dir + "' (it has frames " +
                           std::to_string(all.front().number) + " to " +
                           std::to_string(all.back().number) + "); pick one of those");
}

struct CameraSpec {
  std::vector<double> position, target;  // empty = not given
  double fov = 0;
};

// run.json's camera in the form the command line gives one: empty = not given.
CameraSpec camera_spec(const io::RunInfo& info) {
  CameraSpec c;
  if (!info.camera) return c;
  auto vec = [](const Vec3d& v) { return std::vector<double>{v.x, v.y, v.z}; };
  if (info.camera->position) c.position = vec(*info.camera->position);
  if (info.camera->target) c.target = vec(*info.camera->target);
  c.fov = info.camera->fov;
  return c;
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

// One frame read from disk: what the OpenGL renderer draws, plus the speeds the software
// renderer turns into foam.
struct LoadedFrame {
  render::RenderFrame frame;
  std::vector<float> speed;
};

LoadedFrame load_frame(const std::string& dir, const FrameFiles& f) {
  LoadedFrame out;
  if (!f.fluid.empty()) {
    const std::string path = dir + "/" + f.fluid;
    const io::PointSet ps = fs::path(path).extension() == ".ply" ? io::read_ply_points(path)
                                                                 : io::read_vtu_points(path);
    out.frame.particles = ps.positions;
    const io::DataArray* vel = find_array(ps, "velocity");
    if (vel && !vel->is_int() && vel->components == 3 && vel->values.size() == 3 * ps.size()) {
      out.speed.resize(ps.size());
      for (std::size_t i = 0; i < ps.size(); ++i)
        out.speed[i] = std::sqrt(vel->values[3 * i] * vel->values[3 * i] +
                                 vel->values[3 * i + 1] * vel->values[3 * i + 1] +
                                 vel->values[3 * i + 2] * vel->values[3 * i + 2]);
    }
  }
  if (!f.bodies.empty()) out.frame.meshes = render::body_meshes(io::read_vtu(dir + "/" + f.bodies));
  // Obstacles on a path: this frame's file; those that stay put: one file beside the frames
  // (sim/run.cpp).
  const std::string obstacles =
      f.obstacles.empty() ? dir + "/obstacles.vtu" : dir + "/" + f.obstacles;
  if (fs::exists(obstacles))
    for (render::TriangleMesh& m : render::obstacle_meshes(io::read_vtu(obstacles)))
      out.frame.meshes.push_back(std::move(m));
  return out;
}

Vec3d vec3(const std::vector<double>& v) { return Vec3d(v[0], v[1], v[2]); }

// Automatic framing of the tank, then run.json's camera, then the command line's, part by
// part.
render::Camera choose_camera(const RenderOptions& opt, const CameraSpec& run, const Vec3d& lo,
                             const Vec3d& hi, int width, int height) {
  CameraSpec c = run;
  if (!opt.camera_pos.empty()) c.position = opt.camera_pos;
  if (!opt.camera_target.empty()) c.target = opt.camera_target;
  if (opt.fov > 0) c.fov = opt.fov;
  render::Camera cam = render::auto_frame(lo, hi, width, height, c.fov > 0 ? c.fov : 35.0);
  if (!c.position.empty()) {
    cam.eye = vec3(c.position);
    if (c.target.empty()) cam.target = (lo + hi) * 0.5;
  }
  if (!c.target.empty()) cam.target = vec3(c.target);
  if (norm(cam.target - cam.eye) < 1e-12)
    throw std::runtime_error("the camera's position and target coincide; move one of them");
  return cam;
}

void parse_size(const std::string& size, int* w, int* h) {
  char tail = 0;
  if (std::sscanf(size.c_str(), "%dx%d%c", w, h, &tail) != 2 || *w < 16 || *h < 16 || *w > 16384 ||
      *h > 16384)
    throw std::runtime_error(
        "--size " + size + ": expected WIDTHxHEIGHT between 16x16 and 16384x16384, e.g. 1280x720");
}

// The renderer a command asked for, with the fallback from OpenGL to software said once.
class Painter {
 public:
  explicit Painter(const std::string& which) {
    if (which == "splat") return;
    try {
      gl_ = std::make_unique<render::HeadlessRenderer>();
    } catch (const render::GlUnavailable& e) {
      if (which == "gl")
        throw std::runtime_error(std::string("OpenGL is not available: ") + e.what() +
                                 "; use --renderer splat for the software renderer");
      std::fprintf(stderr,
                   "note: OpenGL is not available (%s); drawing with the software renderer "
                   "(--renderer splat)\n",
                   e.what());
    }
  }
  bool gl() const { return gl_ != nullptr; }
  std::string device() const { return gl_ ? gl_->device() : "software splat renderer"; }

  render::Image draw(const LoadedFrame& f, const render::Camera& cam, const Vec3d& lo,
                     const Vec3d& hi) {
    if (gl_) return gl_->render(f.frame, cam);
    if (!f.frame.meshes.empty() && !warned_meshes_) {
      std::fprintf(stderr, "note: the software renderer draws no bodies, only the fluid\n");
      warned_meshes_ = true;
    }
    return render::render_particles(cam, f.frame.particles, f.speed.empty() ? nullptr : &f.speed,
                                    f.frame.radius, lo, hi);
  }

 private:
  std::unique_ptr<render::HeadlessRenderer> gl_;
  bool warned_meshes_ = false;
};

// `name` on PATH, or an empty string.
std::string find_program(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::string d = dirs.substr(start, end - start);
    const fs::path p = fs::path(d.empty() ? "." : d) / name;
    std::error_code ec;
    if (fs::is_regular_file(p, ec) && access(p.c_str(), X_OK) == 0) return p.string();
    start = end + 1;
  }
  return "";
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string require_ffmpeg() {
  const std::string ffmpeg = find_program("ffmpeg");
  if (ffmpeg.empty())
    throw std::runtime_error(
        "--format mp4 needs ffmpeg, which is not on PATH; install it (apt-get install ffmpeg, "
        "or scripts/install-deps.sh) or use --format png");
  return ffmpeg;
}

// Raw RGB frames piped to ffmpeg, which encodes H.264 (yuv420p, so every player takes it;
// odd sizes are padded to even).
class VideoPipe {
 public:
  VideoPipe(const std::string& ffmpeg, const std::string& path, int width, int height, double fps)
      : path_(path) {
    char geometry[64];
    std::snprintf(geometry, sizeof geometry, "-s %dx%d -framerate %.6g", width, height, fps);
    const std::string cmd =
        shell_quote(ffmpeg) + " -hide_banner -loglevel error -y -f rawvideo -pix_fmt rgb24 " +
        geometry + " -i - -vf " + shell_quote("pad=ceil(iw/2)*2:ceil(ih/2)*2") +
        " -c:v libx264 -pix_fmt yuv420p -crf 18 -movflags +faststart " + shell_quote(path);
    // A dying ffmpeg must give a write error here, not kill this process.
    old_sigpipe_ = std::signal(SIGPIPE, SIG_IGN);
    pipe_ = popen(cmd.c_str(), "w");
    if (!pipe_) {
      std::signal(SIGPIPE, old_sigpipe_);
      throw std::runtime_error("cannot start ffmpeg (" + ffmpeg + ")");
    }
  }
  ~VideoPipe() {
    if (pipe_) pclose(pipe_);
    std::signal(SIGPIPE, old_sigpipe_);
  }
  void write(const render::Image& img) {
    if (std::fwrite(img.rgb.data(), 1, img.rgb.size(), pipe_) != img.rgb.size())
      throw std::runtime_error("ffmpeg stopped taking frames for '" + path_ +
                               "' (its message is above)");
  }
  void finish() {
    const int status = pclose(pipe_);
    pipe_ = nullptr;
    if (status != 0)
      throw std::runtime_error("ffmpeg could not write '" + path_ + "' (its message is above)");
  }

 private:
  std::string path_;
  FILE* pipe_ = nullptr;
  void (*old_sigpipe_)(int) = SIG_DFL;
};

}  // namespace

CLI::App* add_render_command(CLI::App& app, RenderOptions& opt) {
  auto* r = app.add_subcommand(
      "render", "draw a run's frames as PNG images in OUT/images, or as OUT/video.mp4");
  r->add_option("out", opt.out_dir, "folder written by `sphfem run`")->required();
  r->add_option("--size", opt.size, "image size WIDTHxHEIGHT (default 1280x720)");
  r->add_option("--frames", opt.frames, "all, last or a frame number (default all)");
  r->add_option("--format", opt.format, "png (default) or mp4 (needs ffmpeg)")
      ->check(CLI::IsMember({"png", "mp4"}));
  r->add_option("--renderer", opt.renderer,
                "auto (default: OpenGL, software where no OpenGL context can be made), gl or "
                "splat")
      ->check(CLI::IsMember({"auto", "gl", "splat"}));
  r->add_option("--camera-pos", opt.camera_pos, "camera position x,y,z (m)")
      ->expected(3)
      ->delimiter(',');
  r->add_option("--camera-target", opt.camera_target, "point looked at x,y,z (m)")
      ->expected(3)
      ->delimiter(',');
  r->add_option("--fov", opt.fov, "vertical field of view in degrees (default 35)")
      ->check(CLI::Range(1.0, 170.0));
  r->add_option("--fps", opt.fps, "mp4 frame rate (default: the run's output.fps)")
      ->check(CLI::PositiveNumber);
  return r;
}

int run_render(const RenderOptions& opt) {
  const std::string dir = opt.out_dir.empty() ? "." : opt.out_dir;
  if (!fs::is_directory(dir))
    throw std::runtime_error("run folder '" + dir +
                             "' does not exist; make it with `sphfem run SCENE --out " + dir + "`");
  int width = 0, height = 0;
  parse_size(opt.size, &width, &height);
  const std::vector<FrameFiles> all = list_frames(dir);
  if (all.empty())
    throw std::runtime_error("'" + dir +
                             "' holds no frames (no fluid.pvd, bodies.pvd or frames/fluid_*.ply); "
                             "run the scene with `sphfem run SCENE --out " +
                             dir + "` and let it write at least one frame");
  const std::vector<FrameFiles> frames = select_frames(all, opt.frames, dir);

  // Runs from before run.json have only frames: the radius and tank are guessed below.
  const bool known = io::run_info_exists(dir);
  io::RunInfo info = known ? io::read_run_info(dir) : io::RunInfo();
  const bool video = opt.format == "mp4";
  const std::string images = dir + "/images", video_path = dir + "/video.mp4";
  // Every check before the first frame: ffmpeg is there, the renderer starts.
  const std::string ffmpeg = video ? require_ffmpeg() : std::string();
  Painter painter(opt.renderer);
  std::unique_ptr<VideoPipe> pipe;
  if (video)
    pipe = std::make_unique<VideoPipe>(ffmpeg, video_path, width, height,
                                       opt.fps > 0 ? opt.fps : info.fps);
  else
    io::ensure_directory(images);
  render::Camera cam;
  Vec3d lo, hi;
  for (const FrameFiles& f : frames) {
    LoadedFrame lf = load_frame(dir, f);
    if (&f == &frames.front()) {
      if (!known) {
        // An older run without run.json: guess once, from the first frame, so the camera
        // stays put for the rest.
        info.particle_radius = estimate_radius(lf.frame.particles);
        render::RenderFrame probe = lf.frame;
        probe.radius = float(info.particle_radius);
        if (!render::frame_bounds(probe, &info.domain_min, &info.domain_max))
          info.domain_min = info.domain_max = Vec3d();
        std::fprintf(stderr,
                     "%s not found: guessed particle radius %.4g m and the frame's "
                     "bounding box as the tank\n",
                     io::run_json_path(dir).c_str(), info.particle_radius);
      }
      lo = info.domain_min;
      hi = info.domain_max;
      cam = choose_camera(opt, camera_spec(info), lo, hi, width, height);
    }
    lf.frame.radius = float(info.particle_radius);
    lf.frame.has_box = known;
    lf.frame.box_lo = lo;
    lf.frame.box_hi = hi;
    const render::Image img = painter.draw(lf, cam, lo, hi);
    if (video) {
      pipe->write(img);
      continue;
    }
    const std::string stem = fs::path(f.fluid.empty() ? f.bodies : f.fluid).stem().string();
    const std::string out = images + "/" + stem + ".png";
    render::write_png(out, img);
    std::printf("%s\n", out.c_str());
    std::fflush(stdout);
  }
  if (video) {
    pipe->finish();
    std::printf("%zu frame%s in %s\n", frames.size(), frames.size() == 1 ? "" : "s",
                video_path.c_str());
    return 0;
  }
  std::printf("%zu image%s in %s\n", frames.size(), frames.size() == 1 ? "" : "s", images.c_str());
  return 0;
}

namespace {

// About 65k particles: a column of water 40 x 41 x 40 particles in the corner of a tank,
// jittered by a fixed generator so that every run draws the same frame.
LoadedFrame bench_frame() {
  LoadedFrame f;
  const float r = 0.0075f, spacing = 2 * r;
  std::uint32_t s = 12345;
  auto jitter = [&] {
    s = s * 1664525u + 1013904223u;
    return (float(s >> 8) / float(1 << 24) - 0.5f) * 0.2f * spacing;
  };
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 41; ++j)
      for (int i = 0; i < 40; ++i) {
        f.frame.particles.push_back((i + 0.5f) * spacing + jitter());
        f.frame.particles.push_back((j + 0.5f) * spacing + jitter());
        f.frame.particles.push_back((k + 0.5f) * spacing + jitter());
      }
  f.frame.radius = r;
  f.frame.has_box = true;
  f.frame.box_lo = Vec3d(0, 0, 0);
  f.frame.box_hi = Vec3d(1.6, 0.8, 0.6);
  return f;
}

}  // namespace

int run_render_bench(const std::string& out_dir) {
  const LoadedFrame f = bench_frame();
  const int width = 1280, height = 720;
  const render::Camera cam = render::auto_frame(f.frame.box_lo, f.frame.box_hi, width, height);
  std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
  const std::string cpu = cpu_model();
  std::printf("render benchmark on %s: %zu particles at %dx%d\n", cpu.c_str(),
              f.frame.particle_count(), width, height);
  // The machine is often shared: the core count and load average say what the times mean.
  const unsigned cores = std::thread::hardware_concurrency();
  double load = 0;
  if (std::FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &load) != 1) load = 0;
    std::fclose(f);
  }
  std::string csv =
      "date,cpu,cores,load_avg,renderer,device,width,height,particles,frames,ms_per_frame,"
      "ms_min\n";
  using Clock = std::chrono::steady_clock;
  for (const char* which : {"gl", "splat"}) {
    Painter painter(which);
    const int frames = painter.gl() ? 10 : 3;
    painter.draw(f, cam, f.frame.box_lo, f.frame.box_hi);  // warm-up: shader compiles, buffers
    double total = 0, best = 1e300;
    for (int i = 0; i < frames; ++i) {
      const auto t0 = Clock::now();
      painter.draw(f, cam, f.frame.box_lo, f.frame.box_hi);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      total += ms;
      best = std::min(best, ms);
    }
    const std::string device = painter.device();
    std::printf("  %-6s %8.1f ms/frame (min %.1f) over %d frames  [%s]\n", which, total / frames,
                best, frames, device.c_str());
    char line[1024];
    std::snprintf(line, sizeof line, "%s,\"%s\",%u,%.2f,%s,\"%s\",%d,%d,%zu,%d,%.2f,%.2f\n", date,
                  cpu.c_str(), cores, load, which, device.c_str(), width, height,
                  f.frame.particle_count(), frames, total / frames, best);
    csv += line;
  }
  if (!out_dir.empty()) {
    io::ensure_directory(out_dir);
    io::write_file_atomic(out_dir + "/render.csv", csv);
    std::printf("results: %s/render.csv\n", out_dir.c_str());
  }
  return 0;
}
