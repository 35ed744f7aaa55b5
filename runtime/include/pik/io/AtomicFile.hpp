/// \file AtomicFile.hpp
/// \brief Write a file so that readers see either the old file or the complete new one.
///
/// The data go to a hidden temporary file in the destination's own directory (so the
/// final `rename(2)` stays within one file system and is atomic), which is flushed and
/// `fsync`ed before it is renamed over the destination; the directory is then
/// `fsync`ed so that the rename itself survives a power failure. A crash or an error
/// at any point leaves the destination untouched; an error (or an exception thrown
/// while writing) removes the temporary file.
#pragma once

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "pik/io/IoError.hpp"

namespace pik::io {

namespace detail {

inline std::string errno_text(int err) { return std::strerror(err); }

/// Directory part of `path` ("." when there is none).
inline std::string directory_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

/// A unique hidden temporary name next to `path`, created with mkstemp.
inline std::pair<std::string, int> make_temp_next_to(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  if (base.empty()) throw IoError(path, "not a file name (ends in '/')");
  std::string templ = dir + "." + base + ".tmp.XXXXXX";
  std::vector<char> buf(templ.begin(), templ.end());
  buf.push_back('\0');
  const int fd = ::mkstemp(buf.data());
  if (fd < 0) {
    const int err = errno;
    throw IoError(path, "cannot create a temporary file in '" + directory_of(path) +
                            "': " + errno_text(err));
  }
  // mkstemp creates the file 0600; give it the usual permissions (umask applies).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  return {std::string(buf.data()), fd};
}

inline void fsync_path(const std::string& path, int flags, const std::string& what) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    throw IoError(what, "cannot open '" + path + "' to sync it: " + errno_text(err));
  }
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  // Some file systems cannot fsync a directory (EINVAL); the rename is still atomic.
  if (rc != 0 && err != EINVAL) throw IoError(what, "fsync failed: " + errno_text(err));
}

}  // namespace detail

/// A file being written atomically. Write with write(); commit() publishes it under
/// the destination name. Destroying an uncommitted AtomicFile discards it.
class AtomicFile {
 public:
  explicit AtomicFile(std::string path) : path_(std::move(path)) {
    auto [tmp, fd] = detail::make_temp_next_to(path_);
    tmp_ = std::move(tmp);
    file_ = ::fdopen(fd, "wb");
    if (!file_) {
      const int err = errno;
      ::close(fd);
      ::unlink(tmp_.c_str());
      throw IoError(path_, "fdopen failed: " + detail::errno_text(err));
    }
  }
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile() { discard(); }

  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return tmp_; }
  /// Bytes written so far.
  std::size_t size() const { return written_; }

  void write(const void* data, std::size_t n) {
    if (n == 0) return;
    if (!file_) throw IoError(path_, "write after commit or discard");
    if (std::fwrite(data, 1, n, file_) != n) {
      const int err = errno;
      discard();
      throw IoError(path_, "write failed: " + detail::errno_text(err));
    }
    written_ += n;
  }
  void write(const std::string& s) { write(s.data(), s.size()); }

  /// Flush, fsync, rename over the destination, fsync the directory.
  void commit() {
    if (!file_) throw IoError(path_, "commit after commit or discard");
    if (std::fflush(file_) != 0 || ::fsync(::fileno(file_)) != 0) {
      const int err = errno;
      discard();
      throw IoError(path_, "flush failed: " + detail::errno_text(err));
    }
    const int rc = std::fclose(file_);
    file_ = nullptr;
    if (rc != 0) {
      const int err = errno;
      ::unlink(tmp_.c_str());
      throw IoError(path_, "close failed: " + detail::errno_text(err));
    }
    publish(tmp_, path_);
    tmp_.clear();
  }

  /// Drop the temporary file (no-op after commit).
  void discard() noexcept {
    if (file_) {
      std::fclose(file_);
      file_ = nullptr;
    }
    if (!tmp_.empty()) {
      ::unlink(tmp_.c_str());
      tmp_.clear();
    }
  }

  /// fsync `tmp`, rename it to `path`, fsync the directory. Removes `tmp` on failure.
  static void publish(const std::string& tmp, const std::string& path) {
    try {
      detail::fsync_path(tmp, O_RDONLY, path);
    } catch (...) {
      ::unlink(tmp.c_str());
      throw;
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
      const int err = errno;
      ::unlink(tmp.c_str());
      throw IoError(path, "cannot rename the temporary file into place: " +
                              detail::errno_text(err));
    }
    detail::fsync_path(detail::directory_of(path), O_RDONLY | O_DIRECTORY, path);
  }

 private:
  std::string path_;
  std::string tmp_;
  std::FILE* file_ = nullptr;
  std::size_t written_ = 0;
};

/// For libraries that write by file name (HDF5): `write(tmp_path)` fills a temporary
/// file next to `path`, which is then synced and renamed into place. If `write`
/// throws, the temporary file is removed and the destination is untouched.
inline void write_atomically_by_name(const std::string& path,
                                     const std::function<void(const std::string&)>& write) {
  auto [tmp, fd] = detail::make_temp_next_to(path);
  ::close(fd);
  try {
    write(tmp);
  } catch (...) {
    ::unlink(tmp.c_str());
    throw;
  }
  AtomicFile::publish(tmp, path);
}

}  // namespace pik::io
