/// \file CommandLine.hpp
/// \brief A small declarative command-line parser for simulation programs:
///        `--name value` options with defaults, `--flag` switches, `--help`.
///
/// Programs declare each option once (name, default, help text) and read typed
/// values. `--help` prints the usage with defaults and exits 0; an unknown option,
/// a missing or malformed value exits 2 with one clear line on stderr, the usual
/// convention of command-line tools. given() tells whether the user set an option,
/// so a restarted run can reject a changed physical parameter.
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace pik::io {

class CommandLine {
 public:
  CommandLine(std::string program, std::string summary)
      : program_(std::move(program)), summary_(std::move(summary)) {}

  /// Declares `--name VALUE`; `fallback` is the default shown in --help.
  void option(const std::string& name, const std::string& fallback, const std::string& help,
              const std::string& metavar = "X") {
    opts_.push_back({name, fallback, help, metavar, false});
    values_[name] = fallback;
  }
  /// Declares a switch `--name` (false unless given).
  void flag(const std::string& name, const std::string& help) {
    opts_.push_back({name, "", help, "", true});
    values_[name] = "false";
  }

  /// Parses argv; exits 0 after --help, 2 on a usage error.
  void parse(int argc, char** argv) {
    for (int a = 1; a < argc; ++a) {
      std::string arg = argv[a];
      if (arg == "--help" || arg == "-h") {
        usage(stdout);
        std::exit(0);
      }
      std::string value;
      bool inline_value = false;
      if (const auto eq = arg.find('='); arg.rfind("--", 0) == 0 && eq != std::string::npos) {
        value = arg.substr(eq + 1);
        arg = arg.substr(0, eq);
        inline_value = true;
      }
      const Opt* o = find(arg);
      if (!o) fail("unknown option '" + arg + "'");
      if (o->is_flag) {
        if (inline_value) fail("option " + arg + " takes no value");
        values_[arg] = "true";
      } else {
        if (!inline_value) {
          if (a + 1 >= argc) fail("option " + arg + " needs a value (" + o->metavar + ")");
          value = argv[++a];
        }
        values_[arg] = value;
      }
      given_[arg] = true;
    }
  }

  bool given(const std::string& name) const { return given_.count(name) != 0; }
  const std::string& str(const std::string& name) const { return values_.at(checked(name)); }
  bool on(const std::string& name) const { return str(name) == "true"; }
  double real(const std::string& name) const {
    const std::string& s = str(name);
    char* end = nullptr;
    errno = 0;
    double v = std::strtod(s.c_str(), &end);
    // Fractions like 1/256 are how step sizes are usually written.
    if (end != s.c_str() && *end == '/') {
      const char* den = end + 1;
      const double d = std::strtod(den, &end);
      v = d != 0 ? v / d : NAN;
    }
    if (s.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
      fail("option " + name + ": '" + s + "' is not a number");
    return v;
  }
  std::uint64_t count(const std::string& name) const {
    const std::string& s = str(name);
    char* end = nullptr;
    errno = 0;
    const unsigned long long v = std::strtoull(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0' || s[0] == '-' || errno == ERANGE)
      fail("option " + name + ": '" + s + "' is not a non-negative integer");
    return v;
  }

  /// Prints "PROGRAM: error: what" and exits 2.
  [[noreturn]] void fail(const std::string& what) const {
    std::fprintf(stderr, "%s: error: %s (see %s --help)\n", program_.c_str(), what.c_str(),
                 program_.c_str());
    std::exit(2);
  }

  void usage(std::FILE* out) const {
    std::fprintf(out, "usage: %s [options]\n%s\n\noptions:\n", program_.c_str(), summary_.c_str());
    for (const auto& o : opts_) {
      std::string left = o.name + (o.is_flag ? "" : " " + o.metavar);
      std::fprintf(out, "  %-22s %s", left.c_str(), o.help.c_str());
      if (!o.is_flag && !o.fallback.empty()) std::fprintf(out, " [%s]", o.fallback.c_str());
      std::fprintf(out, "\n");
    }
    std::fprintf(out, "  %-22s %s\n", "--help", "print this help and exit");
  }

 private:
  struct Opt {
    std::string name, fallback, help, metavar;
    bool is_flag;
  };
  const Opt* find(const std::string& name) const {
    for (const auto& o : opts_)
      if (o.name == name) return &o;
    return nullptr;
  }
  const std::string& checked(const std::string& name) const {
    if (!find(name)) fail("internal: option " + name + " was never declared");
    return name;
  }

  std::string program_, summary_;
  std::vector<Opt> opts_;
  std::map<std::string, std::string> values_;
  std::map<std::string, bool> given_;
};

}  // namespace pik::io
