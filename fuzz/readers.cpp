#include "readers.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <typeinfo>

#include "sphfem/fem/import.h"
#include "sphfem/io/ply.h"
#include "sphfem/io/run_info.h"
#include "sphfem/io/vtu.h"
#include "sphfem/scene/load.h"
#include "sphfem/sim/checkpoint.h"
#include "sphfem/sim/simulation.h"

namespace sphfem::fuzz {
namespace {

namespace fs = std::filesystem;

// The scene whose checkpoints the Checkpoint reader loads (tests/data/fuzz/checkpoint holds
// seeds written by `sphfem run` of this scene): fluid and a body, so both states are read.
const char* kCheckpointScene = R"({
  "domain": {"min": [0, 0, 0], "max": [0.12, 0.12, 0.12]},
  "simulation": {"duration": 0.01},
  "fluid": {"particle_radius": 0.01, "blocks": [{"min": [0, 0, 0], "max": [0.12, 0.04, 0.12]}]},
  "bodies": [{"name": "box", "shape": "box", "size": [0.04, 0.04, 0.04],
              "position": [0.06, 0.08, 0.06], "resolution": 1}],
  "output": {"fps": 100, "ply": true}
})";

void write(const std::string& path, const char* data, std::size_t n) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(data, std::streamsize(n));
  if (!out) throw std::runtime_error("fuzz: cannot write " + path);
}

// The documented refusal: the file named, on one line.
void check_message(const std::exception& e, const std::string& file) {
  const std::string m = e.what();
  if (m.find(file) == std::string::npos)
    throw FuzzDefect(std::string("message does not name the file '") + file + "': " + m);
  if (m.find('\n') != std::string::npos) throw FuzzDefect("message is not one line: " + m);
}

template <class Documented, class F>
void expect(const std::string& file, F&& read) {
  try {
    read();
  } catch (const Documented& e) { check_message(e, file); } catch (const FuzzDefect&) {
    throw;
  } catch (const std::exception& e) {
    throw FuzzDefect(std::string("undocumented exception ") + typeid(e).name() + ": " + e.what());
  }
}

// FNV-1a as checkpoint.cpp computes its checksum.
std::uint64_t fnv1a(const std::uint8_t* p, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

Simulation& checkpoint_simulation(const std::string& dir) {
  static std::unique_ptr<Simulation> sim;
  if (!sim) {
    const std::string scene = dir + "/checkpoint_scene.json";
    write(scene, kCheckpointScene, std::strlen(kCheckpointScene));
    sim = std::make_unique<Simulation>(load_scene(scene), Backend::Cpu);
  }
  return *sim;
}

void read_checkpoint_input(const std::uint8_t* data, std::size_t size, const std::string& dir) {
  // Random bytes rarely keep a checksum right; make it match (and the payload length), so
  // that the mutations reach the payload's parser and the state's loader.
  constexpr std::size_t kHeader = 36;
  std::vector<std::uint8_t> b(data, data + size);
  if (b.size() >= kHeader + 8) {
    const std::uint64_t payload = b.size() - kHeader - 8;
    std::memcpy(b.data() + 28, &payload, 8);
    const std::uint64_t sum = fnv1a(b.data() + kHeader, std::size_t(payload));
    std::memcpy(b.data() + b.size() - 8, &sum, 8);
  }
  const std::string path = dir + "/checkpoint.bin";
  write(path, reinterpret_cast<const char*>(b.data()), b.size());
  Checkpoint c;
  try {
    c = read_checkpoint(path);
  } catch (const CheckpointError& e) {
    check_message(e, path);
    return;
  } catch (const std::exception& e) {
    throw FuzzDefect(std::string("undocumented exception ") + typeid(e).name() + ": " + e.what());
  }
  // What run --resume does next: a state that does not fit is refused. A state that loads
  // replaces the whole state, so one Simulation serves every input.
  try {
    checkpoint_simulation(dir).load(c.state);
  } catch (const std::invalid_argument&) {
  } catch (const std::exception& e) {
    throw FuzzDefect(std::string("Simulation::load: undocumented exception ") + typeid(e).name() +
                     ": " + e.what());
  }
}

}  // namespace

const char* reader_name(Reader r) {
  switch (r) {
    case Reader::Scene:
      return "scene";
    case Reader::Surface:
      return "surface";
    case Reader::TetGen:
      return "tetgen";
    case Reader::Gmsh:
      return "gmsh";
    case Reader::Checkpoint:
      return "checkpoint";
    case Reader::RunInfo:
      return "run_info";
    case Reader::Vtu:
      return "vtu";
    case Reader::Ply:
      return "ply";
  }
  return "?";
}

std::vector<Reader> all_readers() {
  return {Reader::Scene,      Reader::Surface, Reader::TetGen, Reader::Gmsh,
          Reader::Checkpoint, Reader::RunInfo, Reader::Vtu,    Reader::Ply};
}

void read_input(Reader r, const std::uint8_t* data, std::size_t size, const std::string& dir) {
  fs::create_directories(dir);
  const char* text = reinterpret_cast<const char*>(data);
  switch (r) {
    case Reader::Scene: {
      // Relative mesh paths start at the scene's folder: the surface files of other inputs.
      const std::string path = dir + "/scene.json";
      write(path, text, size);
      expect<SceneError>(path, [&] { load_scene(path); });
      return;
    }
    case Reader::Surface: {
      static const char* const kExt[] = {".obj", ".ply", ".stl"};
      const std::string path = dir + "/surface" + kExt[size ? data[0] % 3 : 0];
      write(path, size ? text + 1 : text, size ? size - 1 : 0);
      expect<MeshError>(path, [&] {
        SurfaceMesh s = load_surface(path);
        check_surface(s);
      });
      return;
    }
    case Reader::TetGen: {
      const std::string all(text, size);
      const std::size_t cut = all.find("\n@@\n");
      const std::string node = all.substr(0, cut);
      const std::string ele = cut == std::string::npos ? "" : all.substr(cut + 4);
      write(dir + "/mesh.node", node.data(), node.size());
      write(dir + "/mesh.ele", ele.data(), ele.size());
      // Either file may be the one at fault; the message names it.
      try {
        load_tet_mesh(dir + "/mesh.node");
      } catch (const MeshError& e) {
        const std::string m = e.what();
        if (m.find(dir + "/mesh.node") == std::string::npos)
          check_message(e, dir + "/mesh.ele");
        else
          check_message(e, dir + "/mesh.node");
      } catch (const std::exception& e) {
        throw FuzzDefect(std::string("undocumented exception ") + typeid(e).name() + ": " +
                         e.what());
      }
      return;
    }
    case Reader::Gmsh: {
      const std::string path = dir + "/mesh.msh";
      write(path, text, size);
      expect<MeshError>(path, [&] { load_tet_mesh(path); });
      return;
    }
    case Reader::Checkpoint:
      read_checkpoint_input(data, size, dir);
      return;
    case Reader::RunInfo: {
      write(io::run_json_path(dir), text, size);
      expect<std::runtime_error>(io::run_json_path(dir), [&] { io::read_run_info(dir); });
      return;
    }
    case Reader::Vtu: {
      const std::string path = dir + "/frame.vtu";
      write(path, text, size);
      expect<std::runtime_error>(path, [&] { io::read_vtu(path); });
      expect<std::runtime_error>(path, [&] { io::read_vtu_points(path); });
      return;
    }
    case Reader::Ply: {
      const std::string path = dir + "/frame.ply";
      write(path, text, size);
      expect<std::runtime_error>(path, [&] { io::read_ply_points(path); });
      return;
    }
  }
}

std::vector<std::string> seed_files(Reader r, const std::string& source_dir) {
  std::vector<std::string> files;
  const fs::path dir = fs::path(source_dir) / "tests/data/fuzz" / reader_name(r);
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().filename().string().rfind("seed_", 0) == 0) files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace sphfem::fuzz
