/// \file Json.cpp
/// \brief The JSON form of reflected records (schema: docs/reflect.md).
///
/// Kept apart from Reflect.cpp so this translation unit needs only LLVM's small
/// JSON writer, not Clang's AST headers.

#include "Reflect.hpp"

#include <llvm/Support/JSON.h>
#include <llvm/Support/raw_ostream.h>

namespace pik::reflect {
namespace {

/// Version of the JSON layout; pikg-gen checks it.
constexpr int kSchemaVersion = 1;

void write_location(llvm::json::OStream& j, const Location& loc) {
  j.attributeObject("location", [&] {
    j.attribute("file", loc.file);
    j.attribute("line", static_cast<int64_t>(loc.line));
    j.attribute("column", static_cast<int64_t>(loc.column));
  });
}

void write_fields(llvm::json::OStream& j, const std::vector<Field>& fields);

void write_field(llvm::json::OStream& j, const Field& f) {
  j.object([&] {
    j.attribute("name", f.name);
    j.attribute("kind", to_string(f.kind));
    j.attribute("type", f.type);
    j.attribute("declared_type", f.declared_type);
    j.attribute("declared_in", f.declared_in);
    j.attribute("offset", static_cast<int64_t>(f.offset));
    j.attribute("size", static_cast<int64_t>(f.size));
    j.attribute("align", static_cast<int64_t>(f.align));
    if (!f.scalar.empty()) j.attribute("scalar", f.scalar);
    if (f.kind == FieldKind::Vector || f.kind == FieldKind::Array) {
      j.attribute("element", f.element);
      j.attribute("count", static_cast<int64_t>(f.count));
    }
    if (f.kind == FieldKind::Vector) j.attribute("access", f.index_access ? "index" : "members");
    if (f.kind == FieldKind::BitField) {
      j.attribute("bit_offset", static_cast<int64_t>(f.bit_offset));
      j.attribute("bit_width", static_cast<int64_t>(f.bit_width));
    }
    if (f.hidden) j.attribute("hidden", true);
    write_location(j, f.location);
    if (f.kind == FieldKind::Record) j.attributeArray("fields", [&] { write_fields(j, f.fields); });
  });
}

void write_fields(llvm::json::OStream& j, const std::vector<Field>& fields) {
  for (const Field& f : fields) write_field(j, f);
}

}  // namespace

std::string to_json(const Result& result, bool pretty) {
  std::string out;
  llvm::raw_string_ostream os(out);
  {
    llvm::json::OStream j(os, pretty ? 2 : 0);
    j.object([&] {
      j.attribute("tool", "pikg-reflect");
      j.attribute("schema", kSchemaVersion);
      j.attributeArray("records", [&] {
        for (const Record& r : result.records) {
          j.object([&] {
            j.attribute("requested", r.requested);
            j.attribute("name", r.name);
            j.attribute("size", static_cast<int64_t>(r.size));
            j.attribute("align", static_cast<int64_t>(r.align));
            j.attribute("trivially_copyable", r.trivially_copyable);
            j.attribute("standard_layout", r.standard_layout);
            write_location(j, r.location);
            j.attributeArray("fields", [&] { write_fields(j, r.fields); });
          });
        }
      });
    });
  }
  os << "\n";
  os.flush();
  return out;
}

}  // namespace pik::reflect
