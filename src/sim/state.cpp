// State hash (include/sphfem/sim/state.h).
#include "sphfem/sim/state.h"

#include <cstdio>
#include <type_traits>
#include <vector>

namespace sphfem {
namespace {

class Fnv {
 public:
  void bytes(const void* p, std::size_t n) {
    const unsigned char* c = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) {
      h_ ^= c[i];
      h_ *= 1099511628211ull;
    }
  }
  template <class T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable<T>::value, "plain values only");
    bytes(&v, sizeof v);
  }
  template <class T>
  void array(const std::vector<T>& a) {
    value(std::uint64_t(a.size()));
    if (!a.empty()) bytes(a.data(), a.size() * sizeof(T));
  }
  std::uint64_t get() const { return h_; }

 private:
  std::uint64_t h_ = 1469598103934665603ull;
};

}  // namespace

std::uint64_t state_hash(const SimState& s) {
  Fnv h;
  h.value(std::uint8_t(s.has_fluid));
  h.value(std::uint8_t(s.has_bodies));
  h.value(s.time);
  if (s.has_fluid) {
    const FluidState& f = s.fluid;
    h.value(f.n);
    h.value(f.time);
    h.value(std::int64_t(f.steps));
    h.value(f.next_id);
    h.value(std::uint8_t(f.capacity_warned));
    h.array(f.emitter_travel);
    h.array(f.x);
    h.array(f.v);
    h.array(f.id);
    h.array(f.warm_div);
    h.array(f.warm_dens);
  }
  if (s.has_bodies) {
    const BodyState& b = s.bodies;
    h.value(b.nodes);
    h.value(b.elements);
    h.value(b.time);
    h.value(std::int64_t(b.steps));
    h.value(std::uint8_t(b.warm));
    h.array(b.x);
    h.array(b.v);
    h.array(b.dv);
    h.array(b.impulse);
    h.array(b.rotation);
  }
  return h.get();
}

std::string hash_hex(std::uint64_t h) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace sphfem
