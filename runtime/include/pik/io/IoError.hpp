/// \file IoError.hpp
/// \brief The exception every pik reader and writer throws: which file, what is wrong.
#pragma once

#include <stdexcept>
#include <string>

namespace pik::io {

/// A failed read or write. `what()` reads "FILE: message", so a program can print it
/// as is; `path()` and `reason()` give the two parts separately.
class IoError : public std::runtime_error {
 public:
  IoError(const std::string& path, const std::string& reason)
      : std::runtime_error(path + ": " + reason), path_(path), reason_(reason) {}

  const std::string& path() const noexcept { return path_; }
  const std::string& reason() const noexcept { return reason_; }

 private:
  std::string path_;
  std::string reason_;
};

}  // namespace pik::io
