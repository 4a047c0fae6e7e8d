// Files that appear whole or not at all: data goes to `path + ".tmp"` in the same folder and
// is renamed into place only after a successful close, so a crash never leaves half a frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "sphfem/io/endian.h"

namespace sphfem::io {

// Output that cannot be written (a folder that cannot be made, a full disk, a file too large):
// the message names the path and the OS reason. `sphfem run` stops at once with exit code 4.
struct WriteError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Creates `dir` and its parents; throws WriteError naming the folder when it cannot
// (e.g. a file of that name is in the way). An empty string means the current folder.
void ensure_directory(const std::string& dir);

// A temporary file that becomes `path` on commit(). Every failure throws std::runtime_error
// naming the path and the OS reason (a WriteError for the OS's refusals); the temporary is
// removed unless commit() succeeded.
class AtomicFile {
 public:
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  void write(const void* data, std::size_t bytes);
  void write(const std::string& text) { write(text.data(), text.size()); }
  // Writes n values in little-endian byte order whatever the host order is.
  template <class T>
  void write_le(const T* data, std::size_t n);
  template <class T>
  void write_le(const std::vector<T>& v) {
    write_le(v.data(), v.size());
  }

  // Flushes, closes and renames the temporary onto the final path.
  void commit();

  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return temp_; }

 private:
  [[noreturn]] void fail(const std::string& what, int err);
  void discard() noexcept;

  std::string path_, temp_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

// Writes a whole file through an AtomicFile: `fill` writes the contents, then it is committed.
void write_file_atomic(const std::string& path, const std::function<void(AtomicFile&)>& fill);
void write_file_atomic(const std::string& path, const std::string& contents);

template <class T>
void AtomicFile::write_le(const T* data, std::size_t n) {
  static_assert(std::is_trivially_copyable_v<T>, "raw writes need trivially copyable types");
  if (host_is_little_endian() || sizeof(T) == 1) {
    write(data, n * sizeof(T));
    return;
  }
  // Big-endian host: swap through a small buffer instead of copying the whole array.
  unsigned char buf[4096];
  constexpr std::size_t per = sizeof(buf) / sizeof(T);
  for (std::size_t i = 0; i < n; i += per) {
    std::size_t m = n - i < per ? n - i : per;
    copy_le(buf, data + i, m, sizeof(T));
    write(buf, m * sizeof(T));
  }
}

}  // namespace sphfem::io
