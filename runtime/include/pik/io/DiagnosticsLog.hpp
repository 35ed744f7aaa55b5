/// \file DiagnosticsLog.hpp
/// \brief A whitespace-separated table of per-step diagnostics (energies, momentum,
///        timings), one row per line, readable by numpy.loadtxt and plot.py.
///
/// The first line is "# name1 name2 ...". Rows are flushed as they are written, so a
/// crashed run leaves every finished row. Resuming at step k (a restart) first drops
/// rows past k, which a run that got beyond its last checkpoint had written, so the
/// log of a restarted run equals the log of an uninterrupted one.
#pragma once

#include <cstdio>
#include <fstream>
#include <sstream>
#include <iterator>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "pik/io/AtomicFile.hpp"
#include "pik/io/IoError.hpp"

namespace pik::io {

class DiagnosticsLog {
 public:
  DiagnosticsLog() = default;

  /// Starts a new log at `path` with these columns; column 0 must be "step".
  /// With `resume_step >= 0`, keeps the existing file's rows with step <= resume_step.
  DiagnosticsLog(const std::string& path, std::vector<std::string> columns,
                 long long resume_step = -1)
      : path_(path), columns_(std::move(columns)) {
    if (columns_.empty() || columns_[0] != "step")
      throw IoError(path_, "diagnostics log: the first column must be 'step'");
    std::string header = "#";
    for (const auto& c : columns_) header += " " + c;
    header += "\n";

    std::string keep = header;
    if (resume_step >= 0) {
      std::ifstream in(path_);
      if (!in) throw IoError(path_, "cannot reopen the diagnostics log to resume it");
      std::string line;
      std::getline(in, line);
      if (line + "\n" != header)
        throw IoError(path_, "diagnostics log has other columns than this run ('" + line + "')");
      for (std::size_t lineno = 2; std::getline(in, line); ++lineno) {
        std::istringstream ss(line);
        long long step = -1;
        if (!(ss >> step)) {
          // A line cut short by a crash is the only kind of damage expected here.
          if (in.peek() == EOF) break;
          throw IoError(path_ + ":" + std::to_string(lineno), "not a diagnostics row");
        }
        if (step <= resume_step) keep += line + "\n";
      }
    }
    AtomicFile f(path_);
    f.write(keep);
    f.commit();
    file_ = std::fopen(path_.c_str(), "a");
    if (!file_) throw IoError(path_, "cannot open for appending: " + detail::errno_text(errno));
  }
  DiagnosticsLog(DiagnosticsLog&& o) noexcept
      : path_(std::move(o.path_)), columns_(std::move(o.columns_)), file_(o.file_) {
    o.file_ = nullptr;
  }
  DiagnosticsLog& operator=(DiagnosticsLog&& o) noexcept {
    std::swap(path_, o.path_);
    std::swap(columns_, o.columns_);
    std::swap(file_, o.file_);
    return *this;
  }
  ~DiagnosticsLog() {
    if (file_) std::fclose(file_);
  }

  bool is_open() const { return file_ != nullptr; }
  const std::string& path() const { return path_; }

  /// Appends one row; values in column order, 17 significant digits.
  void row(const std::vector<double>& values) {
    if (!file_) return;
    if (values.size() != columns_.size())
      throw IoError(path_, "diagnostics row has " + std::to_string(values.size()) +
                               " values for " + std::to_string(columns_.size()) + " columns");
    std::string line;
    for (std::size_t i = 0; i < values.size(); ++i)
      fmt::format_to(std::back_inserter(line), "{}{:.17g}", i == 0 ? "" : " ", values[i]);
    line += "\n";
    if (std::fputs(line.c_str(), file_) < 0 || std::fflush(file_) != 0)
      throw IoError(path_, "write failed: " + detail::errno_text(errno));
  }

 private:
  std::string path_;
  std::vector<std::string> columns_;
  std::FILE* file_ = nullptr;
};

}  // namespace pik::io
