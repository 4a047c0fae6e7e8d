// One entry per reader of outside data, shared by the libFuzzer targets (fuzz/fuzz_*.cpp) and
// the seeded mutation tests of the normal suite (tests/fuzz_readers_test.cpp).
//
// read_input writes the bytes where the reader expects a file and reads it. A reader may
// accept the input or refuse it with its documented error, whose message must name the file
// and stay on one line; anything else (another exception, a message without the file, a crash
// or a sanitizer report) is a defect, thrown here as FuzzDefect or left to crash.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace sphfem::fuzz {

enum class Reader {
  Scene,       // scene JSON with comments (scene/load.h), bodies and all
  Surface,     // OBJ, PLY or STL through Assimp (fem/import.h); the first byte picks the format
  TetGen,      // .node and .ele, split at the first "\n@@\n" (fem/import.h)
  Gmsh,        // .msh, ASCII 2.x or 4.1 (fem/import.h)
  Checkpoint,  // checkpoint.bin (sim/checkpoint.h), its checksum made to match, then loaded
  RunInfo,     // a run folder's run.json (io/run_info.h)
  Vtu,         // a frame, .vtu (io/vtu.h), read as the renderer reads fluid and bodies
  Ply,         // a frame, binary .ply (io/ply.h)
};

struct FuzzDefect : std::logic_error {
  using std::logic_error::logic_error;
};

const char* reader_name(Reader r);
std::vector<Reader> all_readers();

// Reads one input in `dir` (created if missing; files in it are overwritten).
void read_input(Reader r, const std::uint8_t* data, std::size_t size, const std::string& dir);

// The committed seed inputs of a reader: tests/data/fuzz/<name>/seed_* (small valid files);
// `source_dir` is the repository root.
std::vector<std::string> seed_files(Reader r, const std::string& source_dir);

}  // namespace sphfem::fuzz
