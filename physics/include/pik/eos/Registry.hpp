/// \file Registry.hpp
/// \brief Materials by name, so a program's options can say `--core iron --mantle granite`:
///        a table of name -> factory, with the standard materials (granite, iron, ideal
///        gases) and room for a user's own.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <pik/eos/Eos.hpp>
#include <pik/eos/Tillotson.hpp>

namespace pik::eos {

class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Material>()>;

  /// The standard materials: "granite" and "iron" (Tillotson, Melosh 1989),
  /// "ideal-gas-5/3" and "ideal-gas-1.4".
  static Registry standard() {
    Registry r;
    r.add("granite", [] { return std::make_unique<Tillotson>(TillotsonParams::granite()); });
    r.add("iron", [] { return std::make_unique<Tillotson>(TillotsonParams::iron()); });
    r.add("ideal-gas-5/3", [] { return std::make_unique<IdealGas>(5.0 / 3.0); });
    r.add("ideal-gas-1.4", [] { return std::make_unique<IdealGas>(1.4); });
    return r;
  }

  /// Adds (or replaces) a material.
  void add(const std::string& name, Factory f) {
    if (name.empty()) throw Error("material registry: a material needs a name");
    factories_[name] = std::move(f);
  }
  bool has(const std::string& name) const { return factories_.count(name) != 0; }
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& [k, v] : factories_) out.push_back(k);
    return out;
  }
  /// A new instance of `name`; throws naming the known materials if there is none.
  std::unique_ptr<Material> make(const std::string& name) const {
    auto it = factories_.find(name);
    if (it == factories_.end()) {
      std::string known;
      for (const auto& n : names()) known += (known.empty() ? "" : ", ") + n;
      throw Error("unknown material '" + name + "' (known: " + known + ")");
    }
    return it->second();
  }

 private:
  std::map<std::string, Factory> factories_;
};

}  // namespace pik::eos
