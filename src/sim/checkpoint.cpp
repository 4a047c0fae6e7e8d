// Checkpoint files (include/sphfem/sim/checkpoint.h).
#include "sphfem/sim/checkpoint.h"

#include <cstring>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <type_traits>

#include "sphfem/io/atomic_file.h"
#include "sphfem/scene/load.h"

namespace sphfem {
namespace {

constexpr char kMagic[8] = {'S', 'P', 'H', 'F', 'E', 'M', 'C', 'K'};
constexpr std::uint32_t kByteOrder = 0x01020304u;
constexpr std::size_t kHeader = 8 + 4 + 4 + 4 + 8 + 8;

std::uint64_t fnv1a(const char* p, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(p[i]);
    h *= 1099511628211ull;
  }
  return h;
}

// Raw host bytes: the byte-order mark in the header refuses a file of the other order.
class Writer {
 public:
  template <class T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable<T>::value, "plain values only");
    out_.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  template <class T>
  void array(const std::vector<T>& a) {
    value(std::uint64_t(a.size()));
    if (!a.empty()) out_.append(reinterpret_cast<const char*>(a.data()), a.size() * sizeof(T));
  }
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

class Reader {
 public:
  Reader(const char* p, std::size_t n, const std::string& path) : p_(p), n_(n), path_(path) {}
  template <class T>
  void value(T& v) {
    need(sizeof v);
    std::memcpy(&v, p_ + at_, sizeof v);
    at_ += sizeof v;
  }
  // A flag is a byte that must be 0 or 1: any other value in a bool is undefined behaviour
  // (found by UBSan under the checkpoint fuzz test).
  void value(bool& v) {
    std::uint8_t b = 0;
    value(b);
    if (b > 1) fail();
    v = b == 1;
  }
  template <class T>
  void array(std::vector<T>& a) {
    std::uint64_t n = 0;
    value(n);
    if (n > (n_ - at_) / sizeof(T)) fail();
    a.resize(std::size_t(n));
    if (n) std::memcpy(a.data(), p_ + at_, std::size_t(n) * sizeof(T));
    at_ += std::size_t(n) * sizeof(T);
  }
  bool done() const { return at_ == n_; }
  [[noreturn]] void fail() const {
    throw CheckpointError(path_ +
                          ": the checkpoint's contents do not parse (written by another build?); "
                          "run again without --resume");
  }

 private:
  void need(std::size_t k) const {
    if (k > n_ - at_) fail();
  }
  const char* p_;
  std::size_t n_, at_ = 0;
  const std::string& path_;
};

template <class Io, class S>
void fluid_fields(Io& io, S& f) {
  io.value(f.n);
  io.value(f.time);
  io.value(f.steps);
  io.value(f.next_id);
  io.value(f.capacity_warned);
  io.array(f.emitter_travel);
  io.array(f.x);
  io.array(f.v);
  io.array(f.id);
  io.array(f.warm_div);
  io.array(f.warm_dens);
}

template <class Io, class S>
void body_fields(Io& io, S& b) {
  io.value(b.nodes);
  io.value(b.elements);
  io.value(b.time);
  io.value(b.steps);
  io.value(b.warm);
  io.array(b.x);
  io.array(b.v);
  io.array(b.dv);
  io.array(b.impulse);
  io.array(b.rotation);
}

// One list of fields for writing and reading, so the two cannot drift apart.
template <class Io, class C>
void fields(Io& io, C& c) {
  io.value(c.cursor.next_frame);
  io.value(c.cursor.t);
  io.value(c.cursor.t_frame);
  io.value(c.cursor.steps);
  io.value(c.cursor.clamped);
  io.value(c.cursor.crossed);
  io.value(c.cursor.inside_max);
  io.value(c.cursor.last_dt);
  io.array(c.cursor.energy_rotations);
  io.array(c.cursor.frame_times);
  io.value(c.state.has_fluid);
  io.value(c.state.has_bodies);
  io.value(c.state.time);
  if (c.state.has_fluid) fluid_fields(io, c.state.fluid);
  if (c.state.has_bodies) body_fields(io, c.state.bodies);
}

template <class T>
void put(std::string& s, const T& v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

template <class T>
T get(const std::string& s, std::size_t at) {
  T v;
  std::memcpy(&v, s.data() + at, sizeof v);
  return v;
}

}  // namespace

std::uint64_t scene_identity(const SceneSpec& scene) {
  nlohmann::json j = scene_to_json(scene);
  if (j.contains("simulation")) j["simulation"].erase("duration");
  if (j.contains("output")) j["output"].erase("checkpoint_every");
  const std::string text = j.dump();
  return fnv1a(text.data(), text.size());
}

void write_checkpoint(const std::string& path, const Checkpoint& c) {
  Writer w;
  fields(w, c);
  const std::string& payload = w.bytes();
  std::string head(kMagic, sizeof kMagic);
  put(head, kCheckpointVersion);
  put(head, kByteOrder);
  put(head, std::uint32_t(sizeof(Real)));
  put(head, c.scene);
  put(head, std::uint64_t(payload.size()));
  const std::uint64_t sum = fnv1a(payload.data(), payload.size());
  io::write_file_atomic(path, [&](io::AtomicFile& f) {
    f.write(head);
    f.write(payload);
    f.write(&sum, sizeof sum);
  });
}

Checkpoint read_checkpoint(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw CheckpointError(path +
                          ": no checkpoint to resume from; run without --resume (set "
                          "output.checkpoint_every in the scene to write checkpoints)");
  const std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string again = "; run again without --resume";
  if (s.size() < sizeof kMagic || std::memcmp(s.data(), kMagic, sizeof kMagic) != 0)
    throw CheckpointError(path + ": not a sphfem checkpoint" + again);
  if (s.size() < kHeader)
    throw CheckpointError(path + ": the checkpoint is truncated (" + std::to_string(s.size()) +
                          " bytes, shorter than its header)" + again);
  const auto version = get<std::uint32_t>(s, 8);
  if (version != kCheckpointVersion)
    throw CheckpointError(path + ": checkpoint format version " + std::to_string(version) +
                          ", this sphfem reads version " + std::to_string(kCheckpointVersion) +
                          "; resume with the sphfem that wrote it, or run again without --resume");
  if (get<std::uint32_t>(s, 12) != kByteOrder)
    throw CheckpointError(path + ": the checkpoint was written on a machine of another byte order" +
                          again);
  const auto real = get<std::uint32_t>(s, 16);
  if (real != sizeof(Real))
    throw CheckpointError(path + ": the checkpoint holds " + (real == 8 ? "double" : "float") +
                          " values, this sphfem was built for " +
                          (sizeof(Real) == 8 ? "double" : "float") +
                          " (SPHFEM_DOUBLE); resume with the build that wrote it" + again);
  Checkpoint c;
  c.scene = get<std::uint64_t>(s, 20);
  const auto bytes = get<std::uint64_t>(s, 28);
  if (s.size() != kHeader + bytes + 8)
    throw CheckpointError(path + ": the checkpoint is truncated or has trailing bytes (" +
                          std::to_string(s.size()) + " bytes, expected " +
                          std::to_string(kHeader + bytes + 8) + ")" + again);
  const char* payload = s.data() + kHeader;
  if (fnv1a(payload, std::size_t(bytes)) != get<std::uint64_t>(s, kHeader + std::size_t(bytes)))
    throw CheckpointError(path + ": the checkpoint is corrupted (its checksum does not match)" +
                          again);
  Reader r(payload, std::size_t(bytes), path);
  fields(r, c);
  if (!r.done()) r.fail();
  return c;
}

}  // namespace sphfem
