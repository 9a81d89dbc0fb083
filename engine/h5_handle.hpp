#pragma once
// Private helpers of the engine's HDF5 writers (run files, study tables): error messages that name the file and
// the operation, and an owning handle that closes an id with its matching H5?close. Not installed for users.
#include <hdf5.h>

#include <string>
#include <utility>

#include "engine/output_h5.hpp"

namespace mpm::h5 {

// HDF5 prints its error stack to stderr by default; we silence that and build our own messages. The setting is
// per thread in thread-safe builds, so every entry point repeats it (it is cheap).
inline void quiet() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

// The most specific entry of HDF5's error stack (e.g. "unable to open file: ... No such file or directory").
inline std::string hdf5_detail() {
  std::string detail;
  auto innermost = [](unsigned n, const H5E_error2_t* e, void* data) -> herr_t {
    if (n == 0 && e->desc) *static_cast<std::string*>(data) = e->desc;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, innermost, &detail);
  H5Eclear2(H5E_DEFAULT);
  return detail;
}

[[noreturn]] inline void fail(const std::string& file, const std::string& what) {
  const std::string detail = hdf5_detail();
  throw OutputError("HDF5 file '" + file + "': " + what + " failed" + (detail.empty() ? "" : ": " + detail));
}

inline void check(herr_t status, const std::string& file, const std::string& what) {
  if (status < 0) fail(file, what);
}

/// Owns one HDF5 id and closes it with the matching H5?close, so early throws leak nothing.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, -1)), closer_(o.closer_) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, -1);
      closer_ = o.closer_;
    }
    return *this;
  }
  ~Handle() { reset(); }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  hid_t release() { return std::exchange(id_, -1); }
  void reset() {
    if (id_ >= 0) closer_(id_);
    id_ = -1;
  }
  /// Closes now and reports a failed close (the last chance to learn that buffered data did not reach disk).
  void close(const std::string& file);

 private:
  hid_t id_ = -1;
  Closer closer_ = nullptr;
};

inline Handle own(hid_t id, Handle::Closer closer, const std::string& file, const std::string& what) {
  if (id < 0) fail(file, what);
  return Handle(id, closer);
}

inline void Handle::close(const std::string& file) {
  const hid_t id = std::exchange(id_, -1);
  if (id >= 0 && closer_(id) < 0) fail(file, "close");
}

}  // namespace mpm::h5
