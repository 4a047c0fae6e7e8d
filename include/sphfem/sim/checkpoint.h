// A run's checkpoint: the simulation's state (sim/state.h) and the run loop's own counters, in
// one versioned binary file written atomically (a temporary renamed into place), so that a run
// killed at any moment leaves its last complete checkpoint. `sphfem run --resume` continues
// from it bit for bit (docs/design.md, "Checkpoints").
//
// Layout (little-endian): "SPHFEMCK", u32 format version, u32 byte-order mark 0x01020304,
// u32 sizeof(Real), u64 scene identity, u64 payload bytes, payload, u64 FNV-1a of the payload.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "sphfem/fem/mat3.h"
#include "sphfem/scene/spec.h"
#include "sphfem/sim/state.h"

namespace sphfem {

constexpr std::uint32_t kCheckpointVersion = 1;

// What the run loop needs to go on writing the same frames and gauge rows.
struct RunCursor {
  int next_frame = 1;  // the frame the run writes next
  double t = 0;        // s, the run's time
  double t_frame = 0;  // s, time of the last frame written
  long steps = 0;      // steps since the run began
  long clamped = 0;    // particles the last-resort box stopped, summed
  long crossed = 0;    // leak counts of the run so far
  long inside_max = 0;
  double last_dt = 0;                  // s, the last step's length
  std::vector<Quat> energy_rotations;  // the energy meter's warm start (fem/energy.h)
  std::vector<double> frame_times;     // s, of the frames written (the .pvd collections)
};

struct Checkpoint {
  std::uint64_t scene = 0;  // scene_identity() of the scene that wrote it
  RunCursor cursor;
  SimState state;
};

// A checkpoint that cannot be used; the message names the file and the fix.
struct CheckpointError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The scene as far as its state depends on it: every field but simulation.duration and
// output.checkpoint_every, which a resumed run may change.
std::uint64_t scene_identity(const SceneSpec& scene);

// Throws std::runtime_error naming the path when it cannot be written (nothing is left behind).
void write_checkpoint(const std::string& path, const Checkpoint& c);
// Throws CheckpointError for a missing, truncated, corrupted or foreign file.
Checkpoint read_checkpoint(const std::string& path);

}  // namespace sphfem
