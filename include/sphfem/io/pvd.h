// ParaView collection (.pvd) files, so a series of frames opens with its real times.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace sphfem::io {

class PvdCollection {
 public:
  struct Entry {
    double time;
    std::string file;  // relative to the folder of the .pvd file
    int part;
  };

  // Starts an empty collection at `path` (nothing is written until the first add()).
  explicit PvdCollection(std::string path);

  // Records a frame and rewrites the whole .pvd atomically, so it is valid after every frame.
  // Several parts (e.g. fluid and boundary) may share one time.
  void add(double time, const std::string& file, int part = 0);

  // Starts from the entries of an earlier run (a resumed one); the file is rewritten with the
  // next add().
  void restore(std::vector<Entry> entries) { entries_ = std::move(entries); }

  const std::string& path() const { return path_; }
  const std::vector<Entry>& entries() const { return entries_; }

 private:
  std::string path_;
  std::vector<Entry> entries_;
};

}  // namespace sphfem::io
