#pragma once
// Declared node parameters: a parameter is declared once (name, label, type,
// default, range, unit, help, when it applies) and everything else is
// derived from that declaration: validation of values set by a host or read
// from a scene file, the `lodestone nodes` listing and docs/nodes.md, and the
// metadata the C ABI hands out.
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "lodestone/core/base/vec3.h"

namespace lodestone::plugin {

enum class ParamType : int {
  Float = 0,
  Int = 1,
  Bool = 2,
  String = 3,
  Choice = 4,
  Vec3 = 5,
  Direction = 6,
  FloatList = 7
};
const char* toString(ParamType type);

/// A parameter value: Float -> double, Int -> int64, Bool -> bool,
/// String/Choice -> string, Vec3/Direction -> Vec3d, FloatList -> vector.
using ParamValue = std::variant<double, std::int64_t, bool, std::string, Vec3d, std::vector<double>>;

/// A parameter applies only when another (Choice or Bool) parameter has one of
/// some values, e.g. `half_size` when `shape` is `box`.
struct ParamCondition {
  std::string param;                ///< empty: always applies
  std::vector<std::string> values;  ///< choice values (or "true"/"false")
};

struct ParamDecl {
  std::string name;   ///< key in scene files and in the C ABI
  std::string label;  ///< short human-readable name
  ParamType type = ParamType::Float;
  ParamValue defaultValue;                                ///< used by networks; an example value when `required`
  double min = -std::numeric_limits<double>::infinity();  ///< numbers and vector components
  double max = std::numeric_limits<double>::infinity();
  bool minOpen = false, maxOpen = false;  ///< range ends excluded
  std::string unit;                       ///< SI unit, "" when dimensionless
  std::string help;
  std::vector<std::string> choices;  ///< Choice: the allowed values
  bool required = false;             ///< scene files must give it (networks start from the default)
  ParamCondition when;
  /// Another parameter this one replaces when given (remanence replaces
  /// magnetization): the two are alternatives, and setting either on a
  /// network makes it the one used.
  std::string replaces;
  std::size_t minCount = 0, maxCount = std::numeric_limits<std::size_t>::max();  ///< FloatList lengths

  /// "> 0", "in [0, 1]", "" (numbers); for choices "one of a, b".
  std::string describeRange() const;
  /// The default as JSON text.
  std::string defaultText() const;
  /// Throws InvalidArgument "<where>: <name>: expected ..., found ..." (for a
  /// vector or list component "<name>[i]: ...", in the words of the JSON
  /// reader, json_reader.h, so that scene files, network_set_json and the
  /// typed setters say the same) unless `value` has this parameter's type,
  /// is finite and lies in its range; returns it normalised (Direction: unit
  /// length; Int from a whole Float accepted).
  ParamValue check(const ParamValue& value, const std::string& where) const;
};

/// Builders for compact declarations.
ParamDecl floatParam(std::string name, std::string label, double def, std::string unit, std::string help);
ParamDecl intParam(std::string name, std::string label, std::int64_t def, std::int64_t min, std::int64_t max,
                   std::string help);
ParamDecl boolParam(std::string name, std::string label, bool def, std::string help);
ParamDecl stringParam(std::string name, std::string label, std::string def, std::string help);
ParamDecl choiceParam(std::string name, std::string label, std::vector<std::string> choices, std::string def,
                      std::string help);
ParamDecl vec3Param(std::string name, std::string label, Vec3d def, std::string unit, std::string help);
ParamDecl directionParam(std::string name, std::string label, Vec3d def, std::string help);
ParamDecl floatListParam(std::string name, std::string label, std::vector<double> def, std::string unit,
                         std::size_t minCount, std::size_t maxCount, std::string help);

/// Chainable range and condition setters.
ParamDecl&& range(ParamDecl&& p, double min, double max, bool minOpen = false, bool maxOpen = false);
ParamDecl&& positive(ParamDecl&& p);     ///< > 0
ParamDecl&& nonNegative(ParamDecl&& p);  ///< >= 0
ParamDecl&& required(ParamDecl&& p);
ParamDecl&& when(ParamDecl&& p, std::string param, std::vector<std::string> values);

/// The values of one node's parameters, by name.
class ParamSet {
 public:
  ParamSet() = default;
  explicit ParamSet(const std::vector<ParamDecl>& decls);

  bool has(const std::string& name) const { return values_.count(name) != 0; }
  void set(const std::string& name, ParamValue value) { values_[name] = std::move(value); }
  const ParamValue& get(const std::string& name) const;

  double getFloat(const std::string& name) const;
  std::int64_t getInt(const std::string& name) const;
  bool getBool(const std::string& name) const;
  const std::string& getString(const std::string& name) const;
  const Vec3d& getVec3(const std::string& name) const;
  const std::vector<double>& getFloats(const std::string& name) const;
  /// Names set explicitly (rather than defaulted); used for alternatives such
  /// as `remanence` or `magnetization`.
  bool given(const std::string& name) const { return given_.count(name) != 0; }
  void markGiven(const std::string& name) { given_[name] = true; }
  void clearGiven(const std::string& name) { given_.erase(name); }

 private:
  std::map<std::string, ParamValue> values_;
  std::map<std::string, bool> given_;
};

/// Whether `decl` applies given the current values (its condition holds).
bool applies(const ParamDecl& decl, const ParamSet& values);

}  // namespace lodestone::plugin
