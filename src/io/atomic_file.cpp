#include "sphfem/io/atomic_file.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace sphfem::io {
namespace fs = std::filesystem;

void ensure_directory(const std::string& dir) {
  if (dir.empty()) return;
  std::error_code ec, ec2;
  fs::create_directories(dir, ec);
  // Check the result rather than the return value: an existing non-folder is not an error
  // to every implementation of create_directories.
  if (fs::is_directory(dir, ec2)) return;
  std::string reason = fs::exists(dir, ec2) ? "a file of that name is in the way"
                       : ec                 ? ec.message()
                                            : "unknown error";
  throw WriteError("cannot create folder '" + dir + "': " + reason);
}

namespace {

// Adds the folder to the message when it is missing, the usual cause of ENOENT here.
std::string describe(const std::string& path, int err) {
  std::string msg = std::strerror(err);
  if (err == ENOENT) {
    fs::path parent = fs::path(path).parent_path();
    std::error_code ec;
    if (!parent.empty() && !fs::is_directory(parent, ec))
      msg += " (folder '" + parent.string() + "' does not exist)";
  }
  return msg;
}

}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)), temp_(path_ + ".tmp") {
  file_ = std::fopen(temp_.c_str(), "wb");
  if (!file_) {
    int err = errno;
    throw WriteError("cannot write '" + path_ + "': " + describe(temp_, err));
  }
  // Frames are written in many small pieces; a larger buffer keeps syscalls few.
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
}

AtomicFile::~AtomicFile() {
  if (!committed_) discard();
}

void AtomicFile::discard() noexcept {
  if (file_) std::fclose(file_);
  file_ = nullptr;
  std::remove(temp_.c_str());
}

void AtomicFile::fail(const std::string& what, int err) {
  discard();
  throw WriteError(what + " '" + path_ + "': " + describe(temp_, err));
}

void AtomicFile::write(const void* data, std::size_t bytes) {
  if (!file_) throw std::logic_error("write to closed file '" + path_ + "'");
  if (bytes == 0) return;
  errno = 0;
  if (std::fwrite(data, 1, bytes, file_) != bytes) fail("cannot write", errno ? errno : EIO);
}

void AtomicFile::commit() {
  if (!file_) throw std::logic_error("commit of closed file '" + path_ + "'");
  errno = 0;
  if (std::fflush(file_) != 0 || std::ferror(file_)) fail("cannot write", errno ? errno : EIO);
  std::FILE* f = file_;
  file_ = nullptr;
  errno = 0;
  if (std::fclose(f) != 0) fail("cannot close", errno ? errno : EIO);
  if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
    int err = errno;
    std::remove(temp_.c_str());
    throw WriteError("cannot rename '" + temp_ + "' to '" + path_ + "': " + std::strerror(err));
  }
  committed_ = true;
}

void write_file_atomic(const std::string& path, const std::function<void(AtomicFile&)>& fill) {
  AtomicFile file(path);
  fill(file);
  file.commit();
}

void write_file_atomic(const std::string& path, const std::string& contents) {
  write_file_atomic(path, [&](AtomicFile& f) { f.write(contents); });
}

}  // namespace sphfem::io
