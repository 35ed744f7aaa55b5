/// \file test_reflect.cpp
/// \brief Unit tests of pikg-reflect's library: struct sources given as strings,
/// layouts checked against what g++ computes for the very same source.
///
/// Each PIK_TWIN_SOURCE block is compiled twice: by g++ as part of this test (so
/// offsetof/sizeof/alignof are the compiler's own answers) and, as a string, by
/// Clang inside pik::reflect::reflect(). Any disagreement in layout fails a test.

#include "Reflect.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "pik/Vec.hpp"

/// Defines the declarations for g++ and keeps their text in `var` for Clang.
#define PIK_TWIN_SOURCE(var, ...) \
  __VA_ARGS__                     \
  constexpr const char* var = #__VA_ARGS__;

namespace {

using pik::reflect::Diagnostic;
using pik::reflect::Field;
using pik::reflect::FieldKind;
using pik::reflect::Record;
using pik::reflect::Result;

/// Where the in-memory headers of these tests live (never on disk).
constexpr const char* kHeader = "/pikg-reflect-test/particle.hpp";

Result reflect_source(const std::string& source, std::vector<std::string> types,
                      std::vector<std::string> args = {}) {
  pik::reflect::Request request;
  request.header = kHeader;
  request.header_contents = source;
  request.types = std::move(types);
  request.compiler_args = std::move(args);
  request.compiler_args.push_back("-I" PIK_RUNTIME_INCLUDE_DIR);
  return pik::reflect::reflect(request);
}

/// All error texts joined, for failure messages and substring checks.
std::string errors_of(const Result& r) {
  std::string out;
  for (const Diagnostic& d : r.errors) out += d.rendered + "\n";
  return out;
}

const Field& field(const Record& r, const std::string& name) {
  for (const Field& f : r.fields)
    if (f.name == name && !f.hidden) return f;
  ADD_FAILURE() << "no field '" << name << "' in " << r.name;
  static const Field none;
  return none;
}

/// Byte offset of a member in a live object: works for members of base classes
/// and for records that are not standard-layout, where offsetof is not defined.
template <class T, class C, class M>
std::size_t member_offset(M C::*member) {
  const T object{};
  const C& as_base = object;
  return static_cast<std::size_t>(reinterpret_cast<const char*>(&(as_base.*member)) -
                                  reinterpret_cast<const char*>(&object));
}

// ---- plain structs ---------------------------------------------------------------

namespace plain {
PIK_TWIN_SOURCE(kSource,
  struct Body {
    double x;
    float m;
    int id;
    unsigned short flags;
    bool alive;
    signed char tag;
    std::uint64_t key;
  };
)
}  // namespace plain

TEST(Reflect, PlainStructFieldsMatchGcc) {
  const Result r = reflect_source(std::string("#include <cstdint>\n") + plain::kSource, {"Body"});
  ASSERT_TRUE(r.ok()) << errors_of(r);
  ASSERT_EQ(r.records.size(), 1u);
  const Record& rec = r.records[0];
  EXPECT_EQ(rec.name, "Body");
  EXPECT_EQ(rec.requested, "Body");
  EXPECT_EQ(rec.size, sizeof(plain::Body));
  EXPECT_EQ(rec.align, alignof(plain::Body));
  EXPECT_TRUE(rec.trivially_copyable);
  EXPECT_TRUE(rec.standard_layout);
  EXPECT_EQ(rec.location.file, kHeader);
  EXPECT_EQ(rec.location.line, 2u);
  ASSERT_EQ(rec.fields.size(), 7u);
  EXPECT_EQ(field(rec, "x").offset, offsetof(plain::Body, x));
  EXPECT_EQ(field(rec, "m").offset, offsetof(plain::Body, m));
  EXPECT_EQ(field(rec, "id").offset, offsetof(plain::Body, id));
  EXPECT_EQ(field(rec, "flags").offset, offsetof(plain::Body, flags));
  EXPECT_EQ(field(rec, "alive").offset, offsetof(plain::Body, alive));
  EXPECT_EQ(field(rec, "tag").offset, offsetof(plain::Body, tag));
  EXPECT_EQ(field(rec, "key").offset, offsetof(plain::Body, key));
  EXPECT_EQ(field(rec, "x").scalar, "f64");
  EXPECT_EQ(field(rec, "m").scalar, "f32");
  EXPECT_EQ(field(rec, "id").scalar, "s32");
  EXPECT_EQ(field(rec, "flags").scalar, "u16");
  EXPECT_EQ(field(rec, "alive").scalar, "bool");
  EXPECT_EQ(field(rec, "tag").scalar, "s8");
  EXPECT_EQ(field(rec, "key").scalar, "u64");
  EXPECT_EQ(field(rec, "key").declared_type, "std::uint64_t");
  EXPECT_EQ(field(rec, "key").type, "unsigned long");
  EXPECT_EQ(field(rec, "x").kind, FieldKind::Scalar);
  EXPECT_EQ(field(rec, "m").size, sizeof(float));
  // The twin source is stringized onto one line, after the #include line.
  EXPECT_EQ(field(rec, "m").location.line, 2u);
  EXPECT_GT(field(rec, "m").location.column, field(rec, "x").location.column);
}

// ---- padding and alignment --------------------------------------------------------

namespace padded {
PIK_TWIN_SOURCE(kSource,
  struct Padded {
    char c;
    double d;
    short s;
    alignas(32) float f;
    int i;
    char tail;
  };
  struct __attribute__((packed)) Packed {
    char c;
    double d;
    int i;
  };
  struct alignas(64) CacheLine {
    float a;
    double b;
  };
)
}  // namespace padded

TEST(Reflect, PaddingAndAlignmentMatchGcc) {
  const Result r = reflect_source(padded::kSource, {"Padded", "Packed", "CacheLine"});
  ASSERT_TRUE(r.ok()) << errors_of(r);
  ASSERT_EQ(r.records.size(), 3u);
  const Record& p = r.records[0];
  EXPECT_EQ(p.size, sizeof(padded::Padded));
  EXPECT_EQ(p.align, alignof(padded::Padded));
  EXPECT_EQ(field(p, "c").offset, offsetof(padded::Padded, c));
  EXPECT_EQ(field(p, "d").offset, offsetof(padded::Padded, d));
  EXPECT_EQ(field(p, "s").offset, offsetof(padded::Padded, s));
  EXPECT_EQ(field(p, "f").offset, offsetof(padded::Padded, f));
  EXPECT_EQ(field(p, "f").offset, 32u);
  EXPECT_EQ(field(p, "i").offset, offsetof(padded::Padded, i));
  EXPECT_EQ(field(p, "tail").offset, offsetof(padded::Padded, tail));

  const Record& k = r.records[1];
  EXPECT_EQ(k.size, sizeof(padded::Packed));
  EXPECT_EQ(k.align, alignof(padded::Packed));
  EXPECT_EQ(field(k, "d").offset, offsetof(padded::Packed, d));
  EXPECT_EQ(field(k, "i").offset, offsetof(padded::Packed, i));

  const Record& c = r.records[2];
  EXPECT_EQ(c.size, sizeof(padded::CacheLine));
  EXPECT_EQ(c.align, alignof(padded::CacheLine));
  EXPECT_EQ(field(c, "b").offset, offsetof(padded::CacheLine, b));
}

// ---- inheritance: members in both a base and a derived class ------------------

namespace derived {
PIK_TWIN_SOURCE(kSource,
  struct Vec { double x, y, z; };
  struct Core { Vec pos; double mass; };
  struct Tagged { int id; };
  struct Body : Core, Tagged {
    float h;
    char kind;
  };
  struct Shadow : Body {
    double mass;
  };
)
}  // namespace derived

TEST(Reflect, InheritedMembersAreFlattenedWithLayoutOffsets) {
  const Result r = reflect_source(derived::kSource, {"Body", "Shadow"});
  ASSERT_TRUE(r.ok()) << errors_of(r);
  const Record& b = r.records[0];
  EXPECT_FALSE(b.standard_layout);  // members in Core, Tagged and Body
  EXPECT_TRUE(b.trivially_copyable);
  EXPECT_EQ(b.size, sizeof(derived::Body));
  ASSERT_EQ(b.fields.size(), 5u);
  EXPECT_EQ(b.fields[0].name, "pos");
  EXPECT_EQ(b.fields[0].declared_in, "Core");
  EXPECT_EQ(b.fields[2].name, "id");
  EXPECT_EQ(b.fields[2].declared_in, "Tagged");
  EXPECT_EQ(b.fields[4].declared_in, "Body");
  EXPECT_EQ(field(b, "pos").offset, (member_offset<derived::Body>(&derived::Core::pos)));
  EXPECT_EQ(field(b, "mass").offset, (member_offset<derived::Body>(&derived::Core::mass)));
  EXPECT_EQ(field(b, "id").offset, (member_offset<derived::Body>(&derived::Tagged::id)));
  EXPECT_EQ(field(b, "h").offset, (member_offset<derived::Body>(&derived::Body::h)));
  EXPECT_EQ(field(b, "kind").offset, (member_offset<derived::Body>(&derived::Body::kind)));

  // Shadow::mass hides Core::mass: both are listed, the base one marked hidden.
  const Record& s = r.records[1];
  EXPECT_EQ(s.size, sizeof(derived::Shadow));
  int masses = 0;
  for (const Field& f : s.fields) {
    if (f.name != "mass") continue;
    ++masses;
    EXPECT_EQ(f.hidden, f.declared_in == "Core");
  }
  EXPECT_EQ(masses, 2);
  EXPECT_EQ(field(s, "mass").declared_in, "Shadow");
  EXPECT_EQ(field(s, "mass").offset, (member_offset<derived::Shadow>(&derived::Shadow::mass)));
}

// ---- templates, aliases, namespaces, nested records, macros ----------------------

namespace templated {
PIK_TWIN_SOURCE(kSource,
  namespace sim {
  namespace detail { template <class T> struct Triple { T x, y, z; }; }
  template <class T, int N = 1>
  struct Particle {
    detail::Triple<T> pos;
    T mass;
    T extra[N];
    struct Meta { int rank; short level; } meta;
  };
  using ParticleD = Particle<double>;
  typedef Particle<float, 3> ParticleF3;
  }
)
}  // namespace templated

TEST(Reflect, TemplateInstantiationsAndAliases) {
  const Result r = reflect_source(templated::kSource,
      {"sim::Particle<double>", "sim::ParticleD", "sim::ParticleF3", "sim::Particle<float, 3>::Meta"});
  ASSERT_TRUE(r.ok()) << errors_of(r);
  ASSERT_EQ(r.records.size(), 4u);
  const Record& d = r.records[0];
  EXPECT_EQ(d.name, "sim::Particle<double, 1>");
  EXPECT_EQ(d.size, sizeof(templated::sim::Particle<double>));
  EXPECT_EQ(field(d, "mass").offset, offsetof(templated::sim::Particle<double>, mass));
  EXPECT_EQ(field(d, "pos").kind, FieldKind::Vector);
  EXPECT_EQ(field(d, "pos").element, "double");
  EXPECT_EQ(field(d, "pos").count, 3u);
  EXPECT_EQ(field(d, "pos").type, "sim::detail::Triple<double>");
  EXPECT_EQ(field(d, "pos").declared_type, "detail::Triple<double>");  // as written, T substituted

  // The alias names the same record as the spelled-out instantiation.
  EXPECT_EQ(r.records[1].requested, "sim::ParticleD");
  EXPECT_EQ(r.records[1].name, d.name);
  EXPECT_EQ(r.records[1].size, d.size);

  using F3 = templated::sim::Particle<float, 3>;
  const Record& f3 = r.records[2];
  EXPECT_EQ(f3.name, "sim::Particle<float, 3>");
  EXPECT_EQ(f3.size, (sizeof(templated::sim::Particle<float, 3>)));
  const Field& extra = field(f3, "extra");
  EXPECT_EQ(extra.kind, FieldKind::Vector);  // float[3]
  EXPECT_TRUE(extra.index_access);
  EXPECT_EQ(extra.offset, (offsetof(F3, extra)));
  const Field& meta = field(f3, "meta");
  EXPECT_EQ(meta.kind, FieldKind::Record);
  EXPECT_EQ(meta.offset, (offsetof(F3, meta)));
  ASSERT_EQ(meta.fields.size(), 2u);
  EXPECT_EQ(meta.fields[1].offset, (offsetof(F3::Meta, level)));

  // A nested record requested on its own.
  EXPECT_EQ(r.records[3].name, "sim::Particle<float, 3>::Meta");
  EXPECT_EQ(r.records[3].size, sizeof(templated::sim::Particle<float, 3>::Meta));
}

TEST(Reflect, MacrosAndCommandLineDefinitionsAreExpanded) {
  const std::string source =
      "#define DECLARE_VEC(name) double name##_x, name##_y, name##_z\n"
      "#ifndef REAL\n#error REAL must be defined\n#endif\n"
      "struct Body { DECLARE_VEC(pos); REAL mass; };\n";
  const Result r = reflect_source(source, {"Body"}, {"-DREAL=float"});
  ASSERT_TRUE(r.ok()) << errors_of(r);
  const Record& b = r.records[0];
  ASSERT_EQ(b.fields.size(), 4u);
  EXPECT_EQ(b.fields[2].name, "pos_z");
  EXPECT_EQ(field(b, "mass").type, "float");
  EXPECT_EQ(field(b, "mass").offset, 24u);

  // Without the definition the header's own #error is reported.
  const Result missing = reflect_source(source, {"Body"});
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(errors_of(missing).find("REAL must be defined"), std::string::npos);
}

// ---- vector-like members ----------------------------------------------------------------

namespace vectors {
PIK_TWIN_SOURCE(kSource,
  namespace PS {
  template <class T> class Vector3 {
   public:
    T x, y, z;
    Vector3() : x(0), y(0), z(0) {}
    Vector3(const Vector3& s) : x(s.x), y(s.y), z(s.z) {}
    Vector3& operator=(const Vector3& s) { x = s.x; y = s.y; z = s.z; return *this; }
  };
  typedef Vector3<double> F64vec;
  }
  struct XY { float x, y; };
  struct NotVec { double x, y, q; };
  struct Mixed { double x; float y, z; };
  struct EPI {
    pik::Vec3<double> pos;
    pik::Vec4<float> q;
    PS::F64vec vel;
    std::array<double, 3> acc;
    std::array<int, 2> cell;
    std::array<double, 8> hist;
    XY uv;
    NotVec nv;
    Mixed mx;
    double w[2];
  };
)
}  // namespace vectors

TEST(Reflect, VectorLikeMembers) {
  const std::string source = "#include <array>\n#include \"pik/Vec.hpp\"\n" + std::string(vectors::kSource);
  const Result r = reflect_source(source, {"EPI"});
  ASSERT_TRUE(r.ok()) << errors_of(r);
  const Record& e = r.records[0];
  // FDPS's vector has a user copy constructor: the struct is not trivially
  // copyable for C++, yet it is accepted because its bytes are its three values.
  EXPECT_FALSE(e.trivially_copyable);
  EXPECT_EQ(e.size, sizeof(vectors::EPI));

  struct Expect { const char* name; const char* element; const char* scalar; unsigned count; bool index; std::size_t offset; };
  const Expect cases[] = {
      {"pos", "double", "f64", 3, false, offsetof(vectors::EPI, pos)},
      {"q", "float", "f32", 4, false, offsetof(vectors::EPI, q)},
      {"vel", "double", "f64", 3, false, offsetof(vectors::EPI, vel)},
      {"acc", "double", "f64", 3, true, offsetof(vectors::EPI, acc)},
      {"cell", "int", "s32", 2, true, offsetof(vectors::EPI, cell)},
      {"uv", "float", "f32", 2, false, offsetof(vectors::EPI, uv)},
      {"w", "double", "f64", 2, true, offsetof(vectors::EPI, w)},
  };
  for (const Expect& c : cases) {
    SCOPED_TRACE(c.name);
    const Field& f = field(e, c.name);
    EXPECT_EQ(f.kind, FieldKind::Vector);
    EXPECT_EQ(f.element, c.element);
    EXPECT_EQ(f.scalar, c.scalar);
    EXPECT_EQ(f.count, c.count);
    EXPECT_EQ(f.index_access, c.index);
    EXPECT_EQ(f.offset, c.offset);
  }
  EXPECT_EQ(field(e, "vel").type, "PS::Vector3<double>");
  EXPECT_EQ(field(e, "acc").type, "std::array<double, 3>");
  EXPECT_EQ(field(e, "hist").kind, FieldKind::Array);  // 8 components: not a vector
  EXPECT_EQ(field(e, "hist").count, 8u);
  EXPECT_EQ(field(e, "nv").kind, FieldKind::Record);   // x, y, q
  EXPECT_EQ(field(e, "mx").kind, FieldKind::Record);   // mixed element types
}

// ---- errors ----------------------------------------------------------------------------

TEST(Reflect, UnknownTypeIsReportedWithSuggestion) {
  const Result r = reflect_source("namespace nbody { struct Body { double m; }; struct Force { double a; }; }\n",
                                  {"nbody::Bdy", "Force"});
  ASSERT_FALSE(r.ok());
  ASSERT_TRUE(r.records.empty());
  const std::string e = errors_of(r);
  EXPECT_NE(e.find("type 'nbody::Bdy' not found in " + std::string(kHeader)), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean"), std::string::npos) << e;
  EXPECT_NE(e.find("nbody::Force"), std::string::npos) << e;  // unqualified name: the qualified one is suggested
}

TEST(Reflect, BrokenHeaderIsReportedAtItsLine) {
  const Result r = reflect_source("struct Body {\n  double m;\n  undeclared_t q;\n};\n", {"Body"});
  ASSERT_FALSE(r.ok());
  ASSERT_FALSE(r.errors.empty());
  const Diagnostic& d = r.errors[0];
  EXPECT_EQ(d.severity, Diagnostic::Severity::Error);
  EXPECT_EQ(d.location.file, kHeader);
  EXPECT_EQ(d.location.line, 3u);
  EXPECT_EQ(d.location.column, 3u);
  EXPECT_NE(d.message.find("undeclared_t"), std::string::npos);
  EXPECT_EQ(d.rendered.rfind(std::string(kHeader) + ":3:3: error: ", 0), 0u) << d.rendered;
  EXPECT_NE(d.rendered.find("^"), std::string::npos);  // source line and caret
  EXPECT_EQ(d.rendered.find("pikg-reflect-probe"), std::string::npos) << d.rendered;
}

TEST(Reflect, MissingIncludeIsReported) {
  const Result r = reflect_source("#include \"no_such_header.hpp\"\nstruct Body { double m; };\n", {"Body"});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.errors[0].location.line, 1u);
  EXPECT_NE(r.errors[0].message.find("no_such_header.hpp"), std::string::npos);
}

TEST(Reflect, VirtualClassIsRefused) {
  const std::string source =
      "struct Body {\n"
      "  double m;\n"
      "  virtual void kick();\n"
      "};\n"
      "struct Derived : Body { double h; };\n"
      "struct Root { double r; };\n"
      "struct Diamond : virtual Root { double d; };\n";
  for (const char* type : {"Body", "Derived", "Diamond"}) {
    SCOPED_TRACE(type);
    const Result r = reflect_source(source, {type});
    ASSERT_FALSE(r.ok());
    const Diagnostic& d = r.errors[0];
    EXPECT_EQ(d.location.file, kHeader);
    EXPECT_NE(d.message.find("cannot be copied as bytes"), std::string::npos) << d.message;
    ASSERT_GE(r.errors.size(), 2u);
    EXPECT_EQ(r.errors[1].severity, Diagnostic::Severity::Note);
  }
  const Result body = reflect_source(source, {"Body"});
  EXPECT_EQ(body.errors[0].location.line, 1u);
  EXPECT_NE(body.errors[1].message.find("virtual function 'kick'"), std::string::npos);
  EXPECT_EQ(body.errors[1].location.line, 3u);
  const Result diamond = reflect_source(source, {"Diamond"});
  EXPECT_NE(diamond.errors[1].message.find("virtual base class 'Root'"), std::string::npos);
}

TEST(Reflect, NonTriviallyCopyableMemberIsRefused) {
  const Result r = reflect_source("#include <string>\nstruct Named {\n  double m;\n  std::string name;\n};\n",
                                  {"Named"});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.errors[0].location.line, 2u);
  ASSERT_GE(r.errors.size(), 2u);
  EXPECT_EQ(r.errors[1].location.line, 4u);
  EXPECT_NE(r.errors[1].message.find("member 'name'"), std::string::npos) << r.errors[1].message;
}

TEST(Reflect, NonRecordAndIncompleteTypesAreRefused) {
  const Result r = reflect_source("using real = double;\nstruct Later;\n", {"real", "Later"});
  ASSERT_FALSE(r.ok());
  const std::string e = errors_of(r);
  EXPECT_NE(e.find("type 'real' is 'double', not a class, struct or union"), std::string::npos) << e;
  EXPECT_NE(e.find("type 'Later' is declared but not defined"), std::string::npos) << e;
}

TEST(Reflect, TypeNamesCannotInjectCode) {
  const Result r = reflect_source("struct Body { double m; };\n", {"Body; struct Evil { int e; }"});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(errors_of(r).find("is not a C++ type name"), std::string::npos);
}

// ---- JSON ----------------------------------------------------------------------------------

TEST(Reflect, JsonHoldsEveryField) {
  const Result r = reflect_source("#include \"pik/Vec.hpp\"\nnamespace n { struct B { pik::Vec3<float> p; int i : 4; }; }\n",
                                  {"n::B"});
  ASSERT_TRUE(r.ok()) << errors_of(r);
  const std::string json = pik::reflect::to_json(r, false);
  for (const char* piece : {"\"tool\":\"pikg-reflect\"", "\"schema\":1", "\"requested\":\"n::B\"", "\"name\":\"n::B\"",
                            "\"size\":16", "\"align\":4", "\"trivially_copyable\":true", "\"standard_layout\":true",
                            "\"kind\":\"vector\"", "\"type\":\"pik::Vec3<float>\"", "\"element\":\"float\"", "\"count\":3",
                            "\"access\":\"members\"", "\"kind\":\"bitfield\"", "\"bit_offset\":96", "\"bit_width\":4"})
    EXPECT_NE(json.find(piece), std::string::npos) << piece << " missing in " << json;
}

// ---- FDPS and PIKG headers that are not self-contained; several headers -------------------

// What g++ sees for FDPS's vector: a class of three components with its own copy
// constructor, as in FDPS (the user's program includes particle_simulator.hpp first).
namespace PS {
using F64 = double;
using F32 = float;
template <class T>
class Vector3 {
 public:
  T x, y, z;
  Vector3() : x(0), y(0), z(0) {}
  Vector3(const Vector3& s) : x(s.x), y(s.y), z(s.z) {}
};
using F64vec = Vector3<F64>;
using F32vec = Vector3<F32>;
}  // namespace PS

PIK_TWIN_SOURCE(kFdpsUser, struct FdpsFP { PS::F64 mass; PS::F32vec vel; PS::F64vec pos; PS::F64 h; };)

TEST(Reflect, FdpsTypesWithoutTheirHeaderAreReadWithStandIns) {
  const Result r = reflect_source(kFdpsUser, {"FdpsFP"});
  ASSERT_TRUE(r.ok()) << errors_of(r);
  ASSERT_EQ(r.notes.size(), 1u);
  EXPECT_NE(r.notes[0].find("FDPS/PIKG types"), std::string::npos);
  const Record& rec = r.records[0];
  EXPECT_EQ(rec.size, sizeof(FdpsFP));
  for (auto [name, off] : {std::pair{"mass", offsetof(FdpsFP, mass)}, std::pair{"vel", offsetof(FdpsFP, vel)},
                           std::pair{"pos", offsetof(FdpsFP, pos)}, std::pair{"h", offsetof(FdpsFP, h)}})
    EXPECT_EQ(field(rec, name).offset, off) << name;
  EXPECT_EQ(field(rec, "pos").kind, FieldKind::Vector);
  EXPECT_EQ(field(rec, "pos").count, 3u);
  EXPECT_EQ(field(rec, "pos").scalar, "f64");
  EXPECT_EQ(field(rec, "vel").scalar, "f32");
  EXPECT_EQ(field(rec, "pos").declared_type, "PS::F64vec");
}

TEST(Reflect, PikgTypesAndTheFallbackSwitch) {
  const Result r = reflect_source("struct P { PIKG::F32vec pos; PIKG::F32 m; };\n", {"P"});
  ASSERT_TRUE(r.ok()) << errors_of(r);
  EXPECT_EQ(field(r.records[0], "m").offset, 12u);
  pik::reflect::Request q;
  q.header = kHeader, q.header_contents = std::string(kFdpsUser), q.types = {"FdpsFP"};
  q.fdps_types_fallback = false;
  const Result off = pik::reflect::reflect(q);
  ASSERT_FALSE(off.ok());
  EXPECT_NE(errors_of(off).find("undeclared identifier 'PS'"), std::string::npos) << errors_of(off);
}

TEST(Reflect, PreludeAndSeveralHeadersInOrder) {
  // PIKG's three class files: EPI, EPJ and FORCE each in a header, the last using the
  // first's alias; and a prelude that the headers rely on.
  pik::reflect::Request q;
  q.header = "/pikg-reflect-test/epi.hpp";
  q.header_contents = "struct EPI { vec_t pos; real h; };\nusing real_t = real;\n";
  q.extra_files = {{"/pikg-reflect-test/prelude.hpp", "using real = double;\nstruct vec_t { real x, y, z; };\n"},
                   {"/pikg-reflect-test/epj.hpp", "struct EPJ { vec_t pos; float m; };\n"},
                   {"/pikg-reflect-test/force.hpp", "struct FORCE { vec_t acc; real_t pot; };\n"}};
  q.preludes = {"/pikg-reflect-test/prelude.hpp"};
  q.more_headers = {"/pikg-reflect-test/epj.hpp", "/pikg-reflect-test/force.hpp"};
  q.types = {"EPI", "EPJ", "FORCE"};
  const Result r = pik::reflect::reflect(q);
  ASSERT_TRUE(r.ok()) << errors_of(r);
  ASSERT_EQ(r.records.size(), 3u);
  EXPECT_EQ(field(r.records[1], "m").offset, 24u);
  EXPECT_EQ(field(r.records[2], "pot").offset, 24u);
  EXPECT_EQ(field(r.records[2], "acc").kind, FieldKind::Vector);
  // An error in a requested type still names the request, with the include lines above it.
  q.types = {"EPI", "Nope"};
  const Result bad = pik::reflect::reflect(q);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(errors_of(bad).find("type 'Nope' not found"), std::string::npos) << errors_of(bad);
  q.more_headers = {"/pikg-reflect-test/missing.hpp"};
  const Result missing = pik::reflect::reflect(q);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(errors_of(missing).find("missing.hpp: error: cannot read header: no such file"), std::string::npos)
      << errors_of(missing);
}

}  // namespace
