/// \file Reflect.cpp
/// \brief pikg-reflect's Clang side: parse the header, find the requested records,
/// refuse the ones that cannot be copied as bytes, and read their layout.
///
/// How a requested type is found: the tool parses a small in-memory main file that
/// includes the header and then, one line per request,
///
///     using pikg_reflect_probe_<i>_ = <requested type>; static_assert(sizeof(...) > 0, "");
///
/// so Clang itself performs name lookup, alias resolution and template
/// instantiation (`Particle<double>` needs no special handling), and `sizeof`
/// forces the class to be complete. An error on probe line i means request i
/// could not be resolved; errors anywhere else mean the header does not compile.
/// All of Clang's knowledge of the layout then comes from ASTRecordLayout.

#include "Reflect.hpp"

#include <clang/AST/ASTConsumer.h>
#include <clang/AST/ASTContext.h>
#include <clang/AST/DeclCXX.h>
#include <clang/AST/DeclTemplate.h>
#include <clang/AST/RecordLayout.h>
#include <clang/AST/RecursiveASTVisitor.h>
#include <clang/Basic/Diagnostic.h>
#include <clang/Basic/DiagnosticOptions.h>
#include <clang/Basic/FileManager.h>
#include <clang/Frontend/CompilerInstance.h>
#include <clang/Frontend/FrontendAction.h>
#include <clang/Frontend/TextDiagnosticPrinter.h>
#include <clang/Tooling/Tooling.h>
#include <llvm/ADT/SmallString.h>
#include <llvm/Support/FileSystem.h>
#include <llvm/Support/MemoryBuffer.h>
#include <llvm/Support/Path.h>
#include <llvm/Support/Regex.h>
#include <llvm/Support/VirtualFileSystem.h>
#include <llvm/Support/raw_ostream.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <memory>
#include <set>

#ifndef PIK_REFLECT_RESOURCE_DIR
#define PIK_REFLECT_RESOURCE_DIR ""
#endif
#ifndef PIK_REFLECT_CLANG_EXECUTABLE
#define PIK_REFLECT_CLANG_EXECUTABLE "clang"
#endif

namespace pik::reflect {
namespace {

constexpr const char* kProbePrefix = "pikg_reflect_probe_";

/// One diagnostic as Clang reported it, before probe errors are rewritten.
struct RawDiagnostic {
  Diagnostic::Severity severity;
  Location location;
  std::string message;
  std::string rendered;
};

/// State shared by the diagnostic consumer, the AST consumer and reflect().
struct Session {
  unsigned first_probe_line = 2;  // the lines above include the preludes and headers
  std::string main_file;                    // absolute path of the in-memory main file
  std::vector<std::string> types;           // requests, in order
  std::vector<RawDiagnostic> diagnostics;   // errors and their notes
  std::set<std::size_t> failed_probes;      // requests with an error on their probe line
  std::vector<std::optional<Record>> records;
  std::vector<Diagnostic> request_errors;   // errors about a request that has no source position
  std::vector<std::string> known_names;     // records and aliases of the header, for suggestions

  /// The request whose probe line `line` of the main file is, if any.
  std::optional<std::size_t> probe_of_line(unsigned line) const {
    if (line < first_probe_line || line - first_probe_line >= types.size()) return std::nullopt;
    return line - first_probe_line;
  }
};

/// A diagnostic built field by field (brace-initialising the aggregate trips
/// a false -Wmaybe-uninitialized in g++ 12).
Diagnostic make_diagnostic(Diagnostic::Severity severity, Location location, std::string message,
                           std::string rendered) {
  Diagnostic d;
  d.severity = severity;
  d.location = std::move(location);
  d.message = std::move(message);
  d.rendered = std::move(rendered);
  return d;
}

/// Records every error (and the notes that follow it) with its position and
/// with the text Clang's own printer gives it (source line and caret included).
/// Warnings are not pikg-reflect's business and are dropped.
class CollectingConsumer : public clang::DiagnosticConsumer {
 public:
  explicit CollectingConsumer(Session& session)
      : session_(session), opts_(new clang::DiagnosticOptions), stream_(buffer_),
        printer_(stream_, opts_.get()) {
    opts_->ShowColors = false;
  }

  void BeginSourceFile(const clang::LangOptions& lang, const clang::Preprocessor* pp) override {
    printer_.BeginSourceFile(lang, pp);
  }
  void EndSourceFile() override { printer_.EndSourceFile(); }

  void HandleDiagnostic(clang::DiagnosticsEngine::Level level,
                        const clang::Diagnostic& info) override {
    DiagnosticConsumer::HandleDiagnostic(level, info);
    const bool is_error = level >= clang::DiagnosticsEngine::Error;
    if (level == clang::DiagnosticsEngine::Note) {
      if (!last_was_error_) return;  // a note on a dropped warning
    } else {
      last_was_error_ = is_error;
      if (!is_error) return;
    }
    RawDiagnostic d;
    d.severity = is_error ? Diagnostic::Severity::Error : Diagnostic::Severity::Note;
    llvm::SmallString<256> text;
    info.FormatDiagnostic(text);
    d.message = std::string(text);
    if (info.getLocation().isValid() && info.hasSourceManager()) {
      const clang::PresumedLoc p = info.getSourceManager().getPresumedLoc(info.getLocation());
      if (p.isValid()) d.location = Location{p.getFilename(), p.getLine(), p.getColumn()};
    }
    printer_.HandleDiagnostic(level, info);
    stream_.flush();
    d.rendered = std::move(buffer_);
    buffer_.clear();
    while (!d.rendered.empty() && d.rendered.back() == '\n') d.rendered.pop_back();
    // The in-memory main file is an implementation detail: drop it from include stacks.
    const std::string via_main = "In file included from " + session_.main_file + ":1:\n";
    if (llvm::StringRef(d.rendered).startswith(via_main)) d.rendered.erase(0, via_main.size());
    if (is_error && d.location.file == session_.main_file) {
      if (auto probe = session_.probe_of_line(d.location.line)) session_.failed_probes.insert(*probe);
    }
    session_.diagnostics.push_back(std::move(d));
  }

 private:
  Session& session_;
  llvm::IntrusiveRefCntPtr<clang::DiagnosticOptions> opts_;
  std::string buffer_;
  llvm::raw_string_ostream stream_;
  clang::TextDiagnosticPrinter printer_;
  bool last_was_error_ = false;
};

/// Collects the probe aliases and, for "did you mean" suggestions, the names of
/// every record, class template and alias the user's headers declare (system
/// headers are skipped by the caller).
class NameCollector : public clang::RecursiveASTVisitor<NameCollector> {
 public:
  std::map<std::size_t, const clang::TypedefNameDecl*> probes;
  std::vector<std::string> names;

  bool VisitTypedefNameDecl(clang::TypedefNameDecl* d) {
    const llvm::StringRef name = d->getName();
    if (name.startswith(kProbePrefix)) {
      std::size_t index = 0;
      if (!name.drop_front(std::strlen(kProbePrefix)).rtrim('_').getAsInteger(10, index))
        probes[index] = d;
      return true;
    }
    add(d);
    return true;
  }
  bool VisitCXXRecordDecl(clang::CXXRecordDecl* d) {
    if (d->isThisDeclarationADefinition() && !d->isLambda() &&
        !llvm::isa<clang::ClassTemplateSpecializationDecl>(d))
      add(d);
    return true;
  }
  bool VisitClassTemplateDecl(clang::ClassTemplateDecl* d) {
    add(d);
    return true;
  }

 private:
  void add(const clang::NamedDecl* d) {
    if (d->getIdentifier() == nullptr || d->isImplicit()) return;
    names.push_back(d->getQualifiedNameAsString());
  }
};

/// The pik scalar code of an arithmetic type ("f64", "s32", "u8", "bool"), or
/// "" for types kernels cannot hold (long double, __int128, ...).
std::string scalar_code(const clang::ASTContext& ctx, clang::QualType type) {
  type = type.getCanonicalType();
  if (const auto* e = type->getAs<clang::EnumType>()) type = e->getDecl()->getIntegerType();
  const auto* b = type->getAs<clang::BuiltinType>();
  if (b == nullptr) return "";
  const auto bits = std::to_string(ctx.getTypeSize(type));
  switch (b->getKind()) {
    case clang::BuiltinType::Bool: return "bool";
    case clang::BuiltinType::Half:
    case clang::BuiltinType::Float16: return "f16";
    case clang::BuiltinType::Float: return "f32";
    case clang::BuiltinType::Double: return "f64";
    case clang::BuiltinType::Int128:
    case clang::BuiltinType::UInt128: return "";
    default: break;
  }
  if (b->isSignedInteger()) return "s" + bits;
  if (b->isUnsignedInteger()) return "u" + bits;
  return "";
}

/// Reads layouts and checks copyability inside one translation unit.
class LayoutReader {
 public:
  explicit LayoutReader(clang::ASTContext& ctx)
      : ctx_(ctx), canonical_(ctx.getLangOpts()), written_(ctx.getLangOpts()) {
    canonical_.SuppressTagKeyword = true;
    canonical_.FullyQualifiedName = true;
    canonical_.PrintCanonicalTypes = true;
    written_.SuppressTagKeyword = true;
  }

  std::string canonical_name(clang::QualType t) const {
    return t.getCanonicalType().getAsString(canonical_);
  }
  std::string record_name(const clang::CXXRecordDecl* rd) const {
    return canonical_name(ctx_.getRecordType(rd));
  }

  Location location(clang::SourceLocation loc) const {
    const clang::PresumedLoc p = ctx_.getSourceManager().getPresumedLoc(loc);
    if (!p.isValid()) return {};
    return Location{p.getFilename(), p.getLine(), p.getColumn()};
  }

  /// Fields of `rd` (a complete definition), bases first in declaration order,
  /// anonymous structs and unions flattened, offsets relative to `base` bytes.
  void collect(const clang::CXXRecordDecl* rd, std::uint64_t base, const clang::CXXRecordDecl* named,
               std::vector<Field>& out) const {
    const clang::ASTRecordLayout& layout = ctx_.getASTRecordLayout(rd);
    for (const clang::CXXBaseSpecifier& b : rd->bases()) {
      if (b.isVirtual()) continue;  // refused before layouts are read
      const clang::CXXRecordDecl* bd = b.getType()->getAsCXXRecordDecl()->getDefinition();
      collect(bd, base + layout.getBaseClassOffset(bd).getQuantity(), bd, out);
    }
    for (const clang::FieldDecl* f : rd->fields()) {
      if (f->isUnnamedBitfield()) continue;
      const std::uint64_t bits = layout.getFieldOffset(f->getFieldIndex());
      if (f->isAnonymousStructOrUnion()) {
        collect(f->getType()->getAsCXXRecordDecl(), base + bits / 8, named, out);
        continue;
      }
      out.push_back(describe(f, base * 8 + bits, named));
    }
  }

  /// Flattened fields with `hidden` set where a derived class redeclares a name.
  std::vector<Field> fields_of(const clang::CXXRecordDecl* rd) const {
    std::vector<Field> out;
    collect(rd, 0, rd, out);
    for (std::size_t i = 0; i < out.size(); ++i)
      for (std::size_t j = i + 1; j < out.size(); ++j)
        if (out[j].name == out[i].name) out[i].hidden = true;
    return out;
  }

  /// Element type and count when `rd` is a small vector: its only data members are
  /// x, y[, z[, w]] of one arithmetic type, packed without padding (pik::Vec3,
  /// FDPS's PS::F64vec, users' own structs).
  std::optional<std::pair<clang::QualType, unsigned>> vector_like(const clang::CXXRecordDecl* rd) const {
    rd = rd->getDefinition();
    if (rd == nullptr || rd->isInvalidDecl() || rd->isPolymorphic() || rd->getNumVBases() != 0 ||
        rd->isUnion())
      return std::nullopt;
    std::vector<Field> f;
    std::vector<clang::QualType> types;
    collect_types(rd, types);
    collect(rd, 0, rd, f);
    static const char* const kNames[] = {"x", "y", "z", "w"};
    if (f.size() < 2 || f.size() > 4 || types.size() != f.size()) return std::nullopt;
    const clang::QualType elem = types[0].getCanonicalType().getUnqualifiedType();
    if (scalar_code(ctx_, elem).empty() || elem->isEnumeralType() || elem->isBooleanType())
      return std::nullopt;
    const std::uint64_t esize = ctx_.getTypeSizeInChars(elem).getQuantity();
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (f[i].name != kNames[i] || f[i].kind == FieldKind::BitField ||
          types[i].getCanonicalType().getUnqualifiedType() != elem || f[i].offset != i * esize)
        return std::nullopt;
    }
    if (static_cast<std::uint64_t>(ctx_.getTypeSizeInChars(ctx_.getRecordType(rd)).getQuantity()) !=
        f.size() * esize)
      return std::nullopt;
    return std::make_pair(elem, static_cast<unsigned>(f.size()));
  }

  /// Why a record cannot be copied as bytes, as a chain of (position, reason)
  /// steps, or an empty chain when it can. Virtual functions and bases are refused
  /// outright; otherwise a record is accepted when C++ calls it trivially copyable,
  /// when it is a small vector (FDPS's vectors have a member-wise user copy
  /// constructor, which copies exactly their bytes), or when every base and member
  /// is acceptable and the record itself declares no copy, move or destructor.
  using Chain = std::vector<std::pair<clang::SourceLocation, std::string>>;
  Chain why_not_bytes(const clang::CXXRecordDecl* rd, int depth = 0) const {
    rd = rd->getDefinition();
    if (rd == nullptr || depth > 32) return {};
    for (const clang::CXXBaseSpecifier& b : rd->vbases())
      return {{b.getBeginLoc(), "it has virtual base class '" + canonical_name(b.getType()) + "'"}};
    if (rd->isPolymorphic()) {
      for (const clang::CXXMethodDecl* m : rd->methods())
        if (m->isVirtual() && !m->isImplicit())
          return {{m->getLocation(), "it has virtual function '" + m->getNameAsString() + "'"}};
      for (const clang::CXXBaseSpecifier& b : rd->bases()) {
        const clang::CXXRecordDecl* bd = b.getType()->getAsCXXRecordDecl();
        if (bd != nullptr && bd->isPolymorphic()) {
          Chain c{{b.getBeginLoc(), "its base class '" + canonical_name(b.getType()) + "' has virtual functions"}};
          Chain inner = why_not_bytes(bd, depth + 1);
          c.insert(c.end(), inner.begin(), inner.end());
          return c;
        }
      }
      return {{rd->getLocation(), "it has virtual functions"}};
    }
    if (ctx_.getRecordType(rd).isTriviallyCopyableType(ctx_) || vector_like(rd)) return {};
    for (const clang::CXXConstructorDecl* c : rd->ctors())
      if (c->isCopyOrMoveConstructor() && c->isUserProvided())
        return {{c->getLocation(), std::string("it has a user-provided ") +
                                       (c->isCopyConstructor() ? "copy" : "move") + " constructor"}};
    for (const clang::CXXMethodDecl* m : rd->methods())
      if ((m->isCopyAssignmentOperator() || m->isMoveAssignmentOperator()) && m->isUserProvided())
        return {{m->getLocation(), std::string("it has a user-provided ") +
                                       (m->isCopyAssignmentOperator() ? "copy" : "move") +
                                       " assignment operator"}};
    if (const clang::CXXDestructorDecl* d = rd->getDestructor(); d != nullptr && d->isUserProvided())
      return {{d->getLocation(), "it has a user-provided destructor"}};
    for (const clang::CXXBaseSpecifier& b : rd->bases()) {
      if (const clang::CXXRecordDecl* bd = b.getType()->getAsCXXRecordDecl()) {
        Chain inner = why_not_bytes(bd, depth + 1);
        if (!inner.empty()) {
          Chain c{{b.getBeginLoc(), "its base class '" + canonical_name(b.getType()) +
                                        "' cannot be copied as bytes"}};
          c.insert(c.end(), inner.begin(), inner.end());
          return c;
        }
      }
    }
    for (const clang::FieldDecl* f : rd->fields()) {
      const clang::Type* t = f->getType()->getBaseElementTypeUnsafe();
      if (const clang::CXXRecordDecl* fd = t->getAsCXXRecordDecl()) {
        Chain inner = why_not_bytes(fd, depth + 1);
        if (!inner.empty()) {
          Chain c{{f->getLocation(), "member '" + f->getNameAsString() + "' has type '" +
                                         canonical_name(f->getType()) +
                                         "', which cannot be copied as bytes"}};
          c.insert(c.end(), inner.begin(), inner.end());
          return c;
        }
      }
    }
    return {};
  }

 private:
  /// The declared types of the fields collect() returns, in the same order.
  void collect_types(const clang::CXXRecordDecl* rd, std::vector<clang::QualType>& out) const {
    for (const clang::CXXBaseSpecifier& b : rd->bases())
      if (!b.isVirtual()) collect_types(b.getType()->getAsCXXRecordDecl()->getDefinition(), out);
    for (const clang::FieldDecl* f : rd->fields()) {
      if (f->isUnnamedBitfield()) continue;
      if (f->isAnonymousStructOrUnion())
        collect_types(f->getType()->getAsCXXRecordDecl(), out);
      else
        out.push_back(f->getType());
    }
  }

  /// Element type and count of a C array or std::array.
  std::optional<std::pair<clang::QualType, std::uint64_t>> array_parts(clang::QualType t) const {
    t = t.getCanonicalType();
    if (const auto* a = ctx_.getAsConstantArrayType(t))
      return std::make_pair(a->getElementType(), a->getSize().getZExtValue());
    const auto* s = llvm::dyn_cast_or_null<clang::ClassTemplateSpecializationDecl>(t->getAsCXXRecordDecl());
    if (s == nullptr || !s->isInStdNamespace() || s->getName() != "array") return std::nullopt;
    const clang::TemplateArgumentList& args = s->getTemplateArgs();
    if (args.size() != 2 || args[0].getKind() != clang::TemplateArgument::Type ||
        args[1].getKind() != clang::TemplateArgument::Integral)
      return std::nullopt;
    return std::make_pair(args[0].getAsType(), args[1].getAsIntegral().getZExtValue());
  }

  Field describe(const clang::FieldDecl* f, std::uint64_t bit_offset, const clang::CXXRecordDecl* named) const {
    Field out;
    out.name = f->getNameAsString();
    const clang::QualType type = f->getType();
    out.type = canonical_name(type);
    out.declared_type = type.getAsString(written_);
    out.declared_in = record_name(named);
    out.location = location(f->getLocation());
    out.offset = bit_offset / 8;
    if (f->isBitField()) {
      out.kind = FieldKind::BitField;
      out.bit_offset = static_cast<unsigned>(bit_offset);
      out.bit_width = f->getBitWidthValue(ctx_);
      out.scalar = scalar_code(ctx_, type);
      return out;
    }
    out.size = ctx_.getTypeSizeInChars(type).getQuantity();
    out.align = ctx_.getTypeAlignInChars(type).getQuantity();
    const clang::QualType canon = type.getCanonicalType();
    if (canon->isReferenceType() || canon->isMemberPointerType()) {
      out.kind = FieldKind::Other;
    } else if (canon->isPointerType()) {
      out.kind = FieldKind::Pointer;
    } else if (canon->isEnumeralType()) {
      out.kind = FieldKind::Enum;
      out.scalar = scalar_code(ctx_, canon);
    } else if (canon->isBuiltinType()) {
      out.scalar = scalar_code(ctx_, canon);
      out.kind = out.scalar.empty() ? FieldKind::Other : FieldKind::Scalar;
    } else if (auto parts = array_parts(canon)) {
      const clang::QualType elem = parts->first.getCanonicalType();
      out.element = canonical_name(elem);
      out.count = parts->second;
      const bool arithmetic = elem->isBuiltinType() && !elem->isBooleanType();
      out.scalar = arithmetic ? scalar_code(ctx_, elem) : "";
      out.kind = (!out.scalar.empty() && out.count >= 2 && out.count <= 4) ? FieldKind::Vector
                                                                            : FieldKind::Array;
      out.index_access = true;
    } else if (const clang::CXXRecordDecl* rd = canon->getAsCXXRecordDecl()) {
      if (auto v = vector_like(rd)) {
        out.kind = FieldKind::Vector;
        out.element = canonical_name(v->first);
        out.scalar = scalar_code(ctx_, v->first);
        out.count = v->second;
      } else {
        out.kind = FieldKind::Record;
        if (const clang::CXXRecordDecl* def = rd->getDefinition()) out.fields = fields_of(def);
      }
    }
    return out;
  }

  clang::ASTContext& ctx_;
  clang::PrintingPolicy canonical_;
  clang::PrintingPolicy written_;
};

/// After parsing: finds the probes, checks and reads each requested record.
class ReflectConsumer : public clang::ASTConsumer {
 public:
  explicit ReflectConsumer(Session& session) : session_(session) {}

  void HandleTranslationUnit(clang::ASTContext& ctx) override {
    const clang::SourceManager& sm = ctx.getSourceManager();
    NameCollector names;
    for (clang::Decl* d : ctx.getTranslationUnitDecl()->decls())
      if (!sm.isInSystemHeader(d->getLocation())) names.TraverseDecl(d);
    session_.known_names = std::move(names.names);

    LayoutReader reader(ctx);
    clang::DiagnosticsEngine& diags = ctx.getDiagnostics();
    const unsigned refuse_id = diags.getCustomDiagID(
        clang::DiagnosticsEngine::Error,
        "'%0' cannot be copied as bytes, which generated kernels and particle exchange require");
    const unsigned because_id = diags.getCustomDiagID(clang::DiagnosticsEngine::Note, "%0");

    session_.records.assign(session_.types.size(), std::nullopt);
    for (std::size_t i = 0; i < session_.types.size(); ++i) {
      if (session_.failed_probes.count(i) != 0) continue;
      auto it = names.probes.find(i);
      if (it == names.probes.end() || it->second->isInvalidDecl()) continue;
      const clang::QualType type = it->second->getUnderlyingType().getCanonicalType();
      const clang::CXXRecordDecl* rd = type->getAsCXXRecordDecl();
      if (rd == nullptr || (rd = rd->getDefinition()) == nullptr) {
        session_.request_errors.push_back(make_diagnostic(
            Diagnostic::Severity::Error, {},
            "type '" + session_.types[i] + "' is '" + reader.canonical_name(type) +
                "', not a class, struct or union",
            ""));
        continue;
      }
      if (rd->isInvalidDecl()) continue;  // Clang has said why
      const LayoutReader::Chain chain = reader.why_not_bytes(rd);
      if (!chain.empty()) {
        diags.Report(rd->getLocation(), refuse_id) << reader.record_name(rd);
        for (const auto& [loc, why] : chain) diags.Report(loc, because_id) << why;
        continue;
      }
      Record r;
      r.requested = session_.types[i];
      r.name = reader.record_name(rd);
      r.location = reader.location(rd->getLocation());
      r.size = ctx.getTypeSizeInChars(type).getQuantity();
      r.align = ctx.getTypeAlignInChars(type).getQuantity();
      r.trivially_copyable = type.isTriviallyCopyableType(ctx);
      r.standard_layout = rd->isStandardLayout();
      r.fields = reader.fields_of(rd);
      session_.records[i] = std::move(r);
    }
  }

 private:
  Session& session_;
};

class ReflectAction : public clang::ASTFrontendAction {
 public:
  explicit ReflectAction(Session& session) : session_(session) {}
  std::unique_ptr<clang::ASTConsumer> CreateASTConsumer(clang::CompilerInstance&, llvm::StringRef) override {
    return std::make_unique<ReflectConsumer>(session_);
  }

 private:
  Session& session_;
};

/// Characters that could let a --type value escape its probe line.
bool valid_type_name(const std::string& t) {
  if (t.empty() || t.find("//") != std::string::npos || t.find("/*") != std::string::npos) return false;
  return std::none_of(t.begin(), t.end(), [](char c) {
    return c == ';' || c == '{' || c == '}' || c == '#' || c == '"' || c == '\'' || c == '\\' ||
           c == '\n' || c == '\r';
  });
}

/// Names of the header close to `wanted` (edit distance), best first.
std::vector<std::string> suggestions(const std::string& wanted, const std::vector<std::string>& known) {
  llvm::StringRef base(wanted);
  base = base.take_until([](char c) { return c == '<'; }).trim();
  if (base.startswith("::")) base = base.drop_front(2);
  std::vector<std::pair<unsigned, std::string>> scored;
  for (const std::string& k : known) {
    llvm::StringRef name(k);
    const llvm::StringRef last = name.rsplit("::").second.empty() ? name : name.rsplit("::").second;
    const unsigned limit = std::max<unsigned>(2, static_cast<unsigned>(base.size()) / 3);
    const unsigned d = std::min(base.edit_distance(name, true, limit + 1),
                                base.edit_distance(last, true, limit + 1) + (last == name ? 0 : 1));
    if (d <= limit && name != base) scored.emplace_back(d, k);
  }
  std::sort(scored.begin(), scored.end());
  std::vector<std::string> out;
  for (const auto& [d, n] : scored)
    if (std::find(out.begin(), out.end(), n) == out.end() && out.size() < 3) out.push_back(n);
  return out;
}

bool has_option(const std::vector<std::string>& args, llvm::StringRef prefix) {
  return std::any_of(args.begin(), args.end(), [&](const std::string& a) { return llvm::StringRef(a).startswith(prefix); });
}

}  // namespace

std::string resource_dir() {
  if (const char* env = std::getenv("PIKG_REFLECT_RESOURCE_DIR"); env != nullptr && *env != '\0') return env;
  return PIK_REFLECT_RESOURCE_DIR;
}

const char* to_string(FieldKind kind) {
  switch (kind) {
    case FieldKind::Scalar: return "scalar";
    case FieldKind::Vector: return "vector";
    case FieldKind::Array: return "array";
    case FieldKind::Record: return "record";
    case FieldKind::Enum: return "enum";
    case FieldKind::Pointer: return "pointer";
    case FieldKind::BitField: return "bitfield";
    case FieldKind::Other: return "other";
  }
  return "other";
}

namespace {
Result reflect_once(const Request& request);

/// Stand-ins for the scalar and vector types of FDPS (PS::F64, PS::F64vec, ...) and
/// PIKG (PIKG::F64, PIKG::F64vec, ...), for headers that use them without including
/// FDPS or PIKG (FDPS users include particle_simulator.hpp first in their programs).
/// Only the layout matters here: each vector holds its components x, y (, z, w) of
/// the element type, as FDPS's and PIKG's vector classes do, so the offsets read
/// from these are those of the real types.
constexpr const char* kFdpsTypesFile = "pikg-reflect-fdps-pikg-types.hpp";
constexpr const char* kFdpsTypes = R"(#pragma once
namespace pikg_reflect_types {
template <class T> struct Vector2 { T x, y; };
template <class T> struct Vector3 { T x, y, z; };
template <class T> struct Vector4 { T x, y, z, w; };
}
#define PIKG_REFLECT_TYPES(NS) namespace NS { \
  typedef double F64; typedef float F32; typedef long long S64; typedef int S32; \
  typedef unsigned long long U64; typedef unsigned int U32; \
  typedef pikg_reflect_types::Vector3<F64> F64vec; typedef pikg_reflect_types::Vector3<F32> F32vec; \
  typedef pikg_reflect_types::Vector2<F64> F64vec2; typedef pikg_reflect_types::Vector2<F32> F32vec2; \
  typedef pikg_reflect_types::Vector3<F64> F64vec3; typedef pikg_reflect_types::Vector3<F32> F32vec3; \
  typedef pikg_reflect_types::Vector4<F64> F64vec4; typedef pikg_reflect_types::Vector4<F32> F32vec4; }
PIKG_REFLECT_TYPES(PS)
PIKG_REFLECT_TYPES(PIKG)
#undef PIKG_REFLECT_TYPES
)";

bool needs_fdps_types(const Result& r) {
  for (const Diagnostic& d : r.errors) {
    const llvm::StringRef m(d.message);
    if (m.contains("undeclared identifier 'PS'") || m.contains("undeclared identifier 'PIKG'") ||
        m.contains("namespace 'PS'") || m.contains("namespace 'PIKG'"))
      return true;
  }
  return false;
}
}  // namespace

Result reflect(const Request& request) {
  Result result = reflect_once(request);
  if (result.ok() || !request.fdps_types_fallback || !request.preludes.empty() || !needs_fdps_types(result))
    return result;
  // The header uses FDPS's or PIKG's types without including their headers: read it
  // again with the stand-ins above, as PIKG (which never compiles the header) would.
  Request again = request;
  llvm::SmallString<256> dir(request.header);
  llvm::sys::fs::make_absolute(dir);
  llvm::sys::path::remove_filename(dir);
  llvm::sys::path::append(dir, kFdpsTypesFile);
  again.extra_files.emplace_back(std::string(dir), kFdpsTypes);
  again.preludes.push_back(std::string(dir));
  Result retry = reflect_once(again);
  const std::string note = "the header uses FDPS/PIKG types (PS::, PIKG::) without including their headers: "
                           "read with pikg-reflect's stand-ins for their scalar and vector types "
                           "(give --prelude HEADER to use the real ones)";
  if (retry.ok()) retry.notes.push_back(note);
  else
    retry.errors.push_back(make_diagnostic(Diagnostic::Severity::Note, {}, note, "pikg-reflect: note: " + note));
  return retry;
}

namespace {
Result reflect_once(const Request& request) {
  Result result;
  auto fail = [&](std::string message) {
    result.errors.push_back(make_diagnostic(Diagnostic::Severity::Error, {request.header, 0, 0}, message,
                                            request.header + ": error: " + message));
    return result;
  };
  if (request.types.empty()) return fail("no type requested (use --type NAME)");
  for (const std::string& t : request.types)
    if (!valid_type_name(t)) return fail("'" + t + "' is not a C++ type name");

  llvm::SmallString<256> header(request.header);
  llvm::sys::fs::make_absolute(header);
  llvm::sys::path::remove_dots(header, true);
  if (!request.header_contents && llvm::sys::fs::is_directory(header))
    return fail("cannot read header: it is a directory, not a file");
  if (!request.header_contents && !llvm::sys::fs::is_regular_file(header))
    return fail("cannot read header: no such file");

  Session session;
  session.types = request.types;
  llvm::SmallString<256> main_file(llvm::sys::path::parent_path(header));
  llvm::sys::path::append(main_file, llvm::sys::path::stem(header) + ".pikg-reflect-probe.cpp");
  session.main_file = std::string(main_file);

  // The probe main file: the preludes, the header and any more headers, one
  // #include a line, then one probe line per requested type.
  std::string code;
  auto include_line = [&](const std::string& path) {
    llvm::SmallString<256> p(path);
    llvm::sys::fs::make_absolute(p);
    llvm::sys::path::remove_dots(p, true);
    code += "#include \"" + std::string(p) + "\"\n";
  };
  for (const std::string& pre : request.preludes) include_line(pre);
  code += "#include \"" + llvm::sys::path::filename(header).str() + "\"\n";
  for (const std::string& more : request.more_headers) {
    llvm::SmallString<256> p(more);
    llvm::sys::fs::make_absolute(p);
    if (!llvm::sys::fs::is_regular_file(p) &&
        std::none_of(request.extra_files.begin(), request.extra_files.end(),
                     [&](const auto& f) { return f.first == more || f.first == std::string(p); }))
    {
      const std::string m = std::string("cannot read header: ") +
                            (llvm::sys::fs::is_directory(p) ? "it is a directory, not a file" : "no such file");
      result.errors.push_back(make_diagnostic(Diagnostic::Severity::Error, {more, 0, 0}, m, more + ": error: " + m));
      return result;
    }
    include_line(more);
  }
  session.first_probe_line = unsigned(1 + request.preludes.size() + request.more_headers.size() + 1);
  for (std::size_t i = 0; i < request.types.size(); ++i) {
    const std::string alias = kProbePrefix + std::to_string(i) + "_";
    code += "using " + alias + " = " + request.types[i] + "; static_assert(sizeof(" + alias +
            ") > 0, \"\");\n";
  }

  // The files the parser sees: the real file system, with the probe main file
  // (and, for tests, the header itself) laid over it in memory.
  auto overlay = llvm::makeIntrusiveRefCnt<llvm::vfs::OverlayFileSystem>(llvm::vfs::getRealFileSystem());
  auto memory = llvm::makeIntrusiveRefCnt<llvm::vfs::InMemoryFileSystem>();
  overlay->pushOverlay(memory);
  memory->addFile(session.main_file, 0, llvm::MemoryBuffer::getMemBufferCopy(code, session.main_file));
  if (request.header_contents)
    memory->addFile(header, 0, llvm::MemoryBuffer::getMemBufferCopy(*request.header_contents, header));
  for (const auto& [path, contents] : request.extra_files) {
    llvm::SmallString<256> p(path);
    llvm::sys::fs::make_absolute(p);
    memory->addFile(p, 0, llvm::MemoryBuffer::getMemBufferCopy(contents, p));
  }
  auto files = llvm::makeIntrusiveRefCnt<clang::FileManager>(clang::FileSystemOptions(), overlay);

  // Argument 0 names the real clang so the driver finds the same GCC
  // installation (libstdc++ headers) as clang-14 would; defaults come first so
  // the user's own -std= or -resource-dir= wins.
  // -fno-caret-diagnostics only silences Clang's "N errors generated" summary:
  // the messages themselves are rendered by CollectingConsumer's own printer.
  std::vector<std::string> args{PIK_REFLECT_CLANG_EXECUTABLE, "-fsyntax-only", "-xc++",
                                "-fno-caret-diagnostics"};
  if (!has_option(request.compiler_args, "-std=")) args.push_back("-std=c++20");
  if (!has_option(request.compiler_args, "-resource-dir") && !resource_dir().empty())
    args.push_back("-resource-dir=" + resource_dir());
  args.insert(args.end(), request.compiler_args.begin(), request.compiler_args.end());
  args.push_back(session.main_file);

  CollectingConsumer consumer(session);
  clang::tooling::ToolInvocation invocation(args, std::make_unique<ReflectAction>(session), files.get());
  invocation.setDiagnosticConsumer(&consumer);
  const bool ran = invocation.run();

  // Rewrite what Clang said about the probe lines in terms of the request.
  const std::string header_str(header);
  std::set<std::size_t> explained;
  bool dropping = false;  // the last error was a repeat for its request: drop its notes too
  for (RawDiagnostic& d : session.diagnostics) {
    if (d.severity == Diagnostic::Severity::Note && dropping) continue;
    dropping = false;
    if (d.location.file != session.main_file) {
      result.errors.push_back(make_diagnostic(d.severity, d.location, d.message, d.rendered));
      continue;
    }
    const auto probe = session.probe_of_line(d.location.line);
    if (!probe) {  // line 1: the #include itself failed
      result.errors.push_back(
          make_diagnostic(d.severity, {header_str, 0, 0}, d.message, header_str + ": error: " + d.message));
      continue;
    }
    const std::string& type = request.types[*probe];
    if (d.severity == Diagnostic::Severity::Note) {
      const std::string m = "requested here as --type '" + type + "'";
      result.errors.push_back(make_diagnostic(d.severity, {}, m, "pikg-reflect: note: " + m));
      continue;
    }
    if (!explained.insert(*probe).second) {  // one error per request is enough
      dropping = true;
      continue;
    }
    // Clang names the probe alias ("'pikg_reflect_probe_0_' (aka 'Fwd')"): show the user's name only.
    static const llvm::Regex alias_re("'pikg_reflect_probe_[0-9]+_' \\(aka ('[^']*')\\)");
    std::string clang_msg = d.message;
    while (alias_re.match(clang_msg)) clang_msg = alias_re.sub("\\1", clang_msg);
    llvm::StringRef msg(clang_msg);
    const bool incomplete = msg.contains("incomplete type");
    const bool not_found = msg.startswith("unknown type name") || msg.startswith("no type named") ||
                           msg.startswith("no template named") || msg.startswith("use of undeclared") ||
                           msg.startswith("no member named") || msg.contains("does not name a type");
    std::string m;
    if (incomplete) {
      m = "type '" + type + "' is declared but not defined in " + header_str + " (" + clang_msg + ")";
    } else if (not_found) {
      m = "type '" + type + "' not found in " + header_str + ": " + clang_msg;
      if (!msg.contains("did you mean")) {
        const std::vector<std::string> near = suggestions(type, session.known_names);
        for (std::size_t k = 0; k < near.size(); ++k)
          m += (k == 0 ? "; did you mean '" : (k + 1 == near.size() ? "' or '" : "', '")) + near[k];
        if (!near.empty()) m += "'?";
      }
    } else {
      m = "cannot reflect type '" + type + "' from " + header_str + ": " + clang_msg;
    }
    result.errors.push_back(make_diagnostic(d.severity, {header_str, 0, 0}, m, "pikg-reflect: error: " + m));
  }
  for (Diagnostic& d : session.request_errors) {
    d.location.file = header_str;
    d.rendered = "pikg-reflect: error: " + d.message;
    result.errors.push_back(std::move(d));
  }
  if (!ran && result.errors.empty())
    return fail("Clang could not parse the header (no diagnostic was given)");
  if (!result.errors.empty()) return result;
  for (auto& r : session.records) {
    if (!r) return fail("internal error: a requested record was not reflected");
    result.records.push_back(std::move(*r));
  }
  return result;
}

}  // namespace

}  // namespace pik::reflect
