// The run folder's layout and its run.json: what a reader of the folder needs besides the frames.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sphfem/core/vec.h"

namespace sphfem::io {

// Where a run keeps its files, so that the writer and every reader agree on the names.
std::string run_json_path(const std::string& dir);    // <dir>/run.json
std::string frames_dir(const std::string& dir);       // <dir>/frames
std::string gauges_path(const std::string& dir);      // <dir>/gauges.csv
std::string checkpoint_path(const std::string& dir);  // <dir>/checkpoint.bin

// Where pictures of the run look from, as the scene asked; each part may be left to the renderer.
struct RunCamera {
  std::optional<Vec3d> position, target;  // m
  double fov = 0;                         // degrees, vertical; 0 = not given
};

// Everything run.json holds. Plain values (no scene or solver types) so that readers of a
// finished run need none of the simulator.
struct RunInfo {
  std::string scene;  // file the scene was loaded from
  std::string name;
  double particle_radius = 0;    // m
  Vec3d domain_min, domain_max;  // m, inner corners of the tank
  std::string solver;            // "dfsph" or "wcsph"
  std::string backend;           // "cpu" or "cuda"
  double fps = 30;               // frames per simulated second; 30 is what a file without it means
  std::vector<std::string> bodies;  // body names, in scene order
  std::optional<RunCamera> camera;  // absent: frame the tank automatically
};

// Writes <dir>/run.json whole or not at all; throws std::runtime_error naming the file.
void write_run_info(const std::string& dir, const RunInfo& info);

// Reads <dir>/run.json. Throws std::runtime_error naming the file, the field at fault and the
// fix when the file is missing, unreadable or malformed. Only particle_radius and domain are
// required; the other fields default as in RunInfo, as older runs may lack them.
RunInfo read_run_info(const std::string& dir);

// Whether <dir>/run.json exists; runs from before it was written have only frames.
bool run_info_exists(const std::string& dir);

}  // namespace sphfem::io
