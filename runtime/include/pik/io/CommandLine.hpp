/// \file CommandLine.hpp
/// \brief Declarative command lines for simulation programs, on CLI11:
///        `--name value` options with defaults, `--flag` switches, `--help`.
///
/// Programs declare each option once (name, default, help text) and read typed
/// values. Parsing is CLI11's (Debian libcli11-dev): `--name value` and
/// `--name=value`, negative numbers as values, the last of repeated options wins.
/// What a user sees is pik's own: `--help` prints the usage with defaults and
/// exits 0; an unknown option, a missing or malformed value, or a value given to
/// a switch prints one line `PROGRAM: error: ... (see PROGRAM --help)` on stderr
/// and exits 2, the usual convention of command-line tools. given() tells whether
/// the user set an option, so a restarted run can reject a changed physical
/// parameter. real() also reads fractions (`--dt 1/256`).
#pragma once

#include <CLI/CLI.hpp>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <fmt/core.h>

namespace pik::io {

class CommandLine {
 public:
  CommandLine(std::string program, std::string summary)
      : program_(std::move(program)), summary_(std::move(summary)),
        app_(std::make_unique<CLI::App>(summary_, program_)) {
    app_->set_help_flag();  // --help and -h are handled below, with pik's usage text
    app_->add_flag("-h,--help", help_);
    app_->allow_extras();  // unknown arguments are reported as pik reports them
  }
  // Movable, not copyable: CLI11 holds pointers to the values (std::map nodes,
  // which a move keeps in place).
  CommandLine(const CommandLine&) = delete;
  CommandLine& operator=(const CommandLine&) = delete;
  CommandLine(CommandLine&&) = default;
  CommandLine& operator=(CommandLine&&) = default;

  /// Declares `--name VALUE`; `fallback` is the default shown in --help.
  void option(const std::string& name, const std::string& fallback, const std::string& help,
              const std::string& metavar = "X") {
    opts_.push_back({name, fallback, help, metavar, false});
    values_[name] = fallback;
    CLI::Option* o = app_->add_option(name, values_[name], help);
    o->type_name(metavar)->expected(1)->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    o->allow_extra_args(false);
    cli_[name] = o;
  }
  /// Declares a switch `--name` (false unless given).
  void flag(const std::string& name, const std::string& help) {
    opts_.push_back({name, "", help, "", true});
    values_[name] = "false";
    cli_[name] = app_->add_flag(name, help);
  }

  /// Parses argv; exits 0 after --help, 2 on a usage error.
  void parse(int argc, char** argv) {
    // A value glued to a switch (--flag=x) is a mistake CLI11 would read as a boolean.
    for (int a = 1; a < argc; ++a) {
      const std::string arg = argv[a];
      if (arg == "--") break;
      const auto eq = arg.find('=');
      if (arg.rfind("--", 0) == 0 && eq != std::string::npos) {
        const Opt* o = find(arg.substr(0, eq));
        if (o && o->is_flag) fail("option " + o->name + " takes no value");
      }
    }
    try {
      app_->parse(argc, argv);
    } catch (const CLI::ArgumentMismatch& e) {
      // "--name: 1 required X missing": the option is the text before the colon.
      const std::string what = e.what();
      const Opt* o = find(what.substr(0, what.find(':')));
      if (o) fail("option " + o->name + " needs a value (" + o->metavar + ")");
      fail(what);
    } catch (const CLI::ParseError& e) {
      if (help_) {
        usage(stdout);
        std::exit(0);
      }
      fail(e.what());
    }
    if (help_) {
      usage(stdout);
      std::exit(0);
    }
    const std::vector<std::string> rest = app_->remaining();
    if (!rest.empty()) {
      const std::string& arg = rest.front();
      const auto eq = arg.find('=');
      fail("unknown option '" + (arg.rfind("--", 0) == 0 ? arg.substr(0, eq) : arg) + "'");
    }
    for (const auto& o : opts_)
      if (o.is_flag && cli_.at(o.name)->count() > 0) values_[o.name] = "true";
  }

  bool given(const std::string& name) const {
    const auto it = cli_.find(name);
    return it != cli_.end() && it->second->count() > 0;
  }
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
    fmt::print(stderr, "{}: error: {} (see {} --help)\n", program_, what, program_);
    std::exit(2);
  }

  void usage(std::FILE* out) const {
    fmt::print(out, "usage: {} [options]\n{}\n\noptions:\n", program_, summary_);
    for (const auto& o : opts_) {
      const std::string left = o.name + (o.is_flag ? "" : " " + o.metavar);
      fmt::print(out, "  {:<22} {}", left, o.help);
      if (!o.is_flag && !o.fallback.empty()) fmt::print(out, " [{}]", o.fallback);
      fmt::print(out, "\n");
    }
    fmt::print(out, "  {:<22} {}\n", "--help", "print this help and exit");
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
  std::unique_ptr<CLI::App> app_;
  bool help_ = false;
  std::vector<Opt> opts_;
  std::map<std::string, std::string> values_;  // std::map: CLI11 keeps pointers to the values
  std::map<std::string, CLI::Option*> cli_;
};

}  // namespace pik::io
