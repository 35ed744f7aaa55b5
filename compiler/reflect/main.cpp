/// \file main.cpp
/// \brief The `pikg-reflect` command: print the layout of particle structs as JSON.
///
///     pikg-reflect particle.hpp [more.hpp ...] --type Body --type nbody::Force [-o out.json] -- -std=c++20 -Iinclude
///
/// Exit status: 0 on success, 1 when the header or a requested type is rejected
/// (messages on stderr as `file:line:col: error: ...`), 2 on a usage error.

#include "Reflect.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>

#ifndef PIK_VERSION
#define PIK_VERSION "unknown"
#endif

namespace {

constexpr const char* kUsage =
    "usage: pikg-reflect HEADER [HEADER ...] --type NAME [--type NAME ...] [-o OUT.json]\n"
    "                    [--prelude FILE ...] [-- COMPILER-ARGS...]\n"
    "\n"
    "Prints, as JSON, the size, alignment and fields (name, canonical type, offset,\n"
    "size) of each named C++ record declared by the HEADERs (included in the order\n"
    "given, e.g. PIKG's three class files EPI, EPJ, FORCE), as Clang lays it out.\n"
    "\n"
    "  --prelude FILE a header included before the others, for headers that are not\n"
    "                 self-contained (FDPS's particle_simulator.hpp); repeatable. With\n"
    "                 none, a header using FDPS's or PIKG's types (PS::F64vec,\n"
    "                 PIKG::F32) is read with stand-ins of the same layout (a note says so)\n"
    "  --no-fdps-types  never use those stand-ins\n"
    "  --type NAME    a class, struct or alias, qualified as in C++ (nbody::Body,\n"
    "                 Particle<double>); repeatable\n"
    "  -o FILE        write the JSON to FILE instead of standard output\n"
    "  --compact      one-line JSON\n"
    "  --version      print the version\n"
    "  --             everything after it goes to the parser (-std=, -I, -D, ...);\n"
    "                 the default language is -std=c++20\n";

int usage_error(const std::string& message) {
  std::cerr << "pikg-reflect: error: " << message << "\n" << kUsage;
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  pik::reflect::Request request;
  std::string output;
  bool pretty = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    if (a == "--") {
      for (++i; i < argc; ++i) request.compiler_args.emplace_back(argv[i]);
      break;
    }
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      return 0;
    }
    if (a == "--version") {
      std::cout << "pikg-reflect " << PIK_VERSION << " (Clang libTooling)\n";
      return 0;
    }
    if (a == "--compact") {
      pretty = false;
    } else if (a == "--type" || a == "-t") {
      const char* v = value();
      if (v == nullptr) return usage_error("--type needs a type name");
      request.types.emplace_back(v);
    } else if (a.rfind("--type=", 0) == 0) {
      request.types.push_back(a.substr(7));
    } else if (a == "--prelude" || a == "-include") {
      const char* v = value();
      if (v == nullptr) return usage_error(a + " needs a header file name");
      request.preludes.emplace_back(v);
    } else if (a.rfind("--prelude=", 0) == 0) {
      request.preludes.push_back(a.substr(10));
    } else if (a == "--no-fdps-types") {
      request.fdps_types_fallback = false;
    } else if (a == "-o") {
      const char* v = value();
      if (v == nullptr) return usage_error("-o needs a file name");
      output = v;
    } else if (!a.empty() && a[0] == '-') {
      return usage_error("unknown option '" + a + "' (compiler options go after --)");
    } else if (request.header.empty()) {
      request.header = a;
    } else {
      request.more_headers.push_back(a);
    }
  }
  if (request.header.empty()) return usage_error("no header given");
  if (request.types.empty()) return usage_error("no --type given");

  const pik::reflect::Result result = pik::reflect::reflect(request);
  if (!result.ok()) {
    for (const pik::reflect::Diagnostic& d : result.errors) std::cerr << d.rendered << "\n";
    return 1;
  }
  for (const std::string& n : result.notes) std::cerr << "pikg-reflect: note: " << n << "\n";
  const std::string json = pik::reflect::to_json(result, pretty);
  if (output.empty()) {
    std::cout << json;
    return 0;
  }
  std::ofstream out(output);
  if (!(out << json)) {
    std::cerr << "pikg-reflect: error: cannot write '" << output << "': " << std::strerror(errno) << "\n";
    return 1;
  }
  return 0;
}
