/// \file Reflect.hpp
/// \brief pikg-reflect's library interface: read particle structs from a C++ header.
///
/// The header is parsed by Clang (libTooling 14) exactly as a compiler would, so
/// templates, `using` aliases, namespaces, nested records, inheritance and macros
/// all resolve. For every requested type the result holds its size, alignment and
/// flattened field list with offsets from Clang's record layout (the Itanium C++
/// ABI layout that g++ uses too).
///
/// This header is deliberately free of Clang includes: the command-line driver and
/// the unit tests compile against plain standard types only, which keeps their
/// compile time small on a shared two-core machine.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace pik::reflect {

/// A position in a source file (1-based line and column; 0 when unknown).
struct Location {
  std::string file;
  unsigned line = 0;
  unsigned column = 0;
};

/// How a field can be read by a generated kernel.
enum class FieldKind {
  Scalar,    ///< arithmetic value (`scalar` holds its code, e.g. "f64")
  Vector,    ///< 2 to 4 components of one arithmetic type (`element`, `count`)
  Array,     ///< a C array or std::array that is not vector-like
  Record,    ///< another struct/class (its own fields in `fields`)
  Enum,      ///< an enumeration (`scalar` holds the underlying integer code)
  Pointer,   ///< a pointer (kernels cannot use it; reported for completeness)
  BitField,  ///< a bit-field (not addressable: kernels cannot use it)
  Other,     ///< anything else (long double, member pointer, ...)
};

/// One data member of a reflected record, flattened through base classes.
struct Field {
  std::string name;
  std::string type;           ///< canonical type, e.g. "pik::Vec3<double>"
  std::string declared_type;  ///< the type as written, e.g. "nbody::vec_t"
  std::string declared_in;    ///< qualified name of the class that declares it
  std::uint64_t offset = 0;   ///< bytes from the start of the enclosing object
  std::uint64_t size = 0;
  std::uint64_t align = 0;
  FieldKind kind = FieldKind::Other;
  std::string scalar;         ///< "f64", "s32", ... for Scalar/Enum; element code for Vector/Array
  std::string element;        ///< canonical element type for Vector/Array
  std::uint64_t count = 0;    ///< component count for Vector/Array
  bool index_access = false;  ///< Vector: components are `[i]` (arrays), not `.x .y .z .w`
  unsigned bit_offset = 0;    ///< BitField: offset in bits from the start of the object
  unsigned bit_width = 0;     ///< BitField: width in bits
  bool hidden = false;        ///< hidden by a member of the same name in a derived class
  Location location;          ///< where the member is declared
  std::vector<Field> fields;  ///< Record: its fields, offsets relative to this member
};

/// One reflected record.
struct Record {
  std::string requested;  ///< the name given with --type
  std::string name;       ///< fully qualified name, e.g. "nbody::Particle<double>"
  Location location;      ///< where the record is defined
  std::uint64_t size = 0;
  std::uint64_t align = 0;
  bool trivially_copyable = false;  ///< C++'s answer (false for FDPS-style vectors with a user copy constructor)
  bool standard_layout = false;     ///< whether offsetof() is well defined (no members in two classes of a hierarchy)
  std::vector<Field> fields;
};

/// An error (or a note attached to one).
struct Diagnostic {
  enum class Severity { Error, Note };
  Severity severity = Severity::Error;
  Location location;     ///< empty file when the message concerns no source position
  std::string message;   ///< the message alone
  std::string rendered;  ///< full text as printed: "file:line:col: error: ..." plus source line and caret
};

/// What to reflect.
struct Request {
  std::string header;                                  ///< path of the header to read
  std::optional<std::string> header_contents;          ///< in-memory contents (tests); read from disk when empty
  std::vector<std::pair<std::string, std::string>> extra_files;  ///< more in-memory files: path, contents
  std::vector<std::string> types;                      ///< C++ type names, e.g. "nbody::Particle<double>"
  std::vector<std::string> compiler_args;              ///< e.g. -std=c++20 -Iinclude -DDIM=3
  std::vector<std::string> more_headers;               ///< further headers, included after `header` in order
  std::vector<std::string> preludes;                   ///< headers included before `header` (FDPS's particle_simulator.hpp)
  /// When the headers use FDPS's or PIKG's types (PS::F64vec, PIKG::F32) without
  /// including them and no prelude is given, read them again with stand-ins for
  /// those types (same layout) and say so in Result::notes.
  bool fdps_types_fallback = true;
};

/// The outcome: records in request order when `errors` is empty.
struct Result {
  std::vector<Record> records;
  std::vector<Diagnostic> errors;  ///< errors and their notes, in the order found
  std::vector<std::string> notes;  ///< remarks on a successful result (printed to stderr as notes)
  bool ok() const { return errors.empty(); }
};

/// Parses the header and reflects every requested type. Never throws for a user's
/// mistake: an unknown type, a record that cannot be copied as bytes or a header
/// that does not compile is reported in Result::errors.
Result reflect(const Request& request);

/// The records of a successful result as JSON (schema in docs/reflect.md).
std::string to_json(const Result& result, bool pretty = true);

/// The name of a FieldKind as used in the JSON ("scalar", "vector", ...).
const char* to_string(FieldKind kind);

/// The Clang resource directory (builtin headers such as <stddef.h>) that the
/// tool passes to the parser: $PIKG_REFLECT_RESOURCE_DIR when set, else the
/// directory found when pikg-reflect was configured.
std::string resource_dir();

}  // namespace pik::reflect
