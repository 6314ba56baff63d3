#include "lodestone/plugin/param.h"

#include <cmath>
#include <sstream>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/json_reader.h"

namespace lodestone::plugin {

const char* toString(ParamType type) {
  switch (type) {
    case ParamType::Float:
      return "float";
    case ParamType::Int:
      return "int";
    case ParamType::Bool:
      return "bool";
    case ParamType::String:
      return "string";
    case ParamType::Choice:
      return "choice";
    case ParamType::Vec3:
      return "vec3";
    case ParamType::Direction:
      return "direction";
    case ParamType::FloatList:
      return "float list";
  }
  return "?";
}

namespace {

std::string number(double v) {
  std::ostringstream os;
  os.precision(15);
  os << v;
  return os.str();
}

// A value as the JSON reader describes what it found: `number -5`,
// `string "abc"`, `an array of 3 elements`...
std::string describeValue(const ParamValue& v) {
  if (const double* d = std::get_if<double>(&v)) return describeJsonValue(*d);
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return describeJsonValue(*i);
  if (const bool* b = std::get_if<bool>(&v)) return describeJsonValue(*b);
  if (const std::string* t = std::get_if<std::string>(&v)) return describeJsonValue(*t);
  if (const Vec3d* x = std::get_if<Vec3d>(&v)) return describeJsonValue(nlohmann::json{x->x, x->y, x->z});
  return describeJsonValue(nlohmann::json(std::get<std::vector<double>>(v)));
}

}  // namespace

std::string ParamDecl::describeRange() const {
  if (type == ParamType::Choice) {
    std::string s = "one of ";
    for (std::size_t k = 0; k < choices.size(); ++k) s += (k ? ", " : "") + choices[k];
    return s;
  }
  if (type == ParamType::Int && std::isfinite(min) && std::isfinite(max))
    return concat("in [", std::int64_t(min), ", ", std::int64_t(max), "]");
  const bool lo = std::isfinite(min), hi = std::isfinite(max);
  if (lo && hi)
    return std::string("in ") + (minOpen ? "(" : "[") + number(min) + ", " + number(max) + (maxOpen ? ")" : "]");
  if (lo) return std::string(minOpen ? "> " : ">= ") + number(min);
  if (hi) return std::string(maxOpen ? "< " : "<= ") + number(max);
  return "";
}

std::string ParamDecl::defaultText() const {
  const ParamValue& v = defaultValue;
  if (const double* d = std::get_if<double>(&v)) return number(*d);
  if (const std::int64_t* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const bool* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (const std::string* s = std::get_if<std::string>(&v)) return "\"" + *s + "\"";
  if (const Vec3d* x = std::get_if<Vec3d>(&v))
    return "[" + number(x->x) + ", " + number(x->y) + ", " + number(x->z) + "]";
  const auto& list = std::get<std::vector<double>>(v);
  std::string s = "[";
  for (std::size_t k = 0; k < list.size(); ++k) s += (k ? ", " : "") + number(list[k]);
  return s + "]";
}

ParamValue ParamDecl::check(const ParamValue& value, const std::string& where) const {
  // The JSON reader's words (json_reader.h), so that a value set on a node
  // and the same value in a scene file or network_set_json read alike.
  const auto failAt = [&](const std::string& at, const std::string& expected, const std::string& found) {
    throw InvalidArgument(concat(where, ": ", at, ": expected ", expected, ", found ", found));
  };
  const auto fail = [&](const std::string& expected) { failAt(name, expected, describeValue(value)); };
  const Range r{min, max, minOpen, maxOpen};
  // One number of this parameter: finite and in range, else a message at `at`.
  const auto checkNumber = [&](double v, const std::string& at) {
    const std::string expected = numberExpectation("a number", unit, r);
    if (!std::isfinite(v)) failAt(at, expected, concat("a non-finite number (", formatNumber(v), ")"));
    if (!r.contains(v)) failAt(at, expected, describeJsonValue(v));
  };
  switch (type) {
    case ParamType::Float: {
      double v = 0;
      if (const double* d = std::get_if<double>(&value))
        v = *d;
      else if (const std::int64_t* i = std::get_if<std::int64_t>(&value))
        v = double(*i);
      else
        fail(numberExpectation("a number", unit, r));
      checkNumber(v, name);
      return v;
    }
    case ParamType::Int: {
      const std::string expected = concat("an integer in [", std::int64_t(min), ", ", std::int64_t(max), "]");
      std::int64_t v = 0;
      if (const std::int64_t* i = std::get_if<std::int64_t>(&value)) {
        v = *i;
      } else if (const double* d = std::get_if<double>(&value)) {
        if (!std::isfinite(*d)) failAt(name, expected, concat("a non-finite number (", formatNumber(*d), ")"));
        if (std::floor(*d) != *d) failAt(name, expected, "the non-integer " + describeValue(value));
        if (!(std::fabs(*d) < 9e15)) fail(expected);
        v = std::int64_t(*d);
      } else {
        fail(expected);
      }
      if (!r.contains(double(v))) fail(expected);
      return v;
    }
    case ParamType::Bool:
      if (!std::holds_alternative<bool>(value)) fail("true or false");
      return value;
    case ParamType::String:
      if (!std::holds_alternative<std::string>(value)) fail("a string");
      return value;
    case ParamType::Choice: {
      const std::string expected = "one of " + quoteList(choices);
      const std::string* s = std::get_if<std::string>(&value);
      if (!s) fail(expected);
      for (const std::string& c : choices)
        if (c == *s) return value;
      failAt(name, expected, concat("'", *s, "'", didYouMean(*s, choices)));
      break;
    }
    case ParamType::Vec3:
    case ParamType::Direction: {
      const Vec3d* x = std::get_if<Vec3d>(&value);
      if (!x) fail(numberExpectation("an array of 3 numbers [x, y, z]", type == ParamType::Vec3 ? unit : "", r));
      for (int a = 0; a < 3; ++a) checkNumber((*x)[a], concat(name, "[", a, "]"));
      if (type == ParamType::Direction) {
        const double n = norm(*x);
        if (!(n > 0) || !std::isfinite(n)) failAt(name, "a non-zero direction vector [x, y, z]", "[0, 0, 0]");
        return *x / n;
      }
      return value;
    }
    case ParamType::FloatList: {
      const auto* list = std::get_if<std::vector<double>>(&value);
      if (!list || list->size() < minCount || list->size() > maxCount)
        fail(numberExpectation(arrayOf(minCount, maxCount, "numbers"), unit, r));
      for (std::size_t k = 0; k < list->size(); ++k) checkNumber((*list)[k], concat(name, "[", k, "]"));
      return value;
    }
  }
  return value;
}

namespace {
ParamDecl make(std::string name, std::string label, ParamType type, ParamValue def, std::string unit,
               std::string help) {
  ParamDecl p;
  p.name = std::move(name);
  p.label = std::move(label);
  p.type = type;
  p.defaultValue = std::move(def);
  p.unit = std::move(unit);
  p.help = std::move(help);
  return p;
}
}  // namespace

ParamDecl floatParam(std::string name, std::string label, double def, std::string unit, std::string help) {
  return make(std::move(name), std::move(label), ParamType::Float, def, std::move(unit), std::move(help));
}
ParamDecl intParam(std::string name, std::string label, std::int64_t def, std::int64_t min, std::int64_t max,
                   std::string help) {
  ParamDecl p = make(std::move(name), std::move(label), ParamType::Int, def, "", std::move(help));
  p.min = double(min);
  p.max = double(max);
  return p;
}
ParamDecl boolParam(std::string name, std::string label, bool def, std::string help) {
  return make(std::move(name), std::move(label), ParamType::Bool, def, "", std::move(help));
}
ParamDecl stringParam(std::string name, std::string label, std::string def, std::string help) {
  return make(std::move(name), std::move(label), ParamType::String, std::move(def), "", std::move(help));
}
ParamDecl choiceParam(std::string name, std::string label, std::vector<std::string> choices, std::string def,
                      std::string help) {
  ParamDecl p = make(std::move(name), std::move(label), ParamType::Choice, std::move(def), "", std::move(help));
  p.choices = std::move(choices);
  return p;
}
ParamDecl vec3Param(std::string name, std::string label, Vec3d def, std::string unit, std::string help) {
  return make(std::move(name), std::move(label), ParamType::Vec3, def, std::move(unit), std::move(help));
}
ParamDecl directionParam(std::string name, std::string label, Vec3d def, std::string help) {
  return make(std::move(name), std::move(label), ParamType::Direction, def, "", std::move(help));
}
ParamDecl floatListParam(std::string name, std::string label, std::vector<double> def, std::string unit,
                         std::size_t minCount, std::size_t maxCount, std::string help) {
  ParamDecl p =
      make(std::move(name), std::move(label), ParamType::FloatList, std::move(def), std::move(unit), std::move(help));
  p.minCount = minCount;
  p.maxCount = maxCount;
  return p;
}

ParamDecl&& range(ParamDecl&& p, double min, double max, bool minOpen, bool maxOpen) {
  p.min = min;
  p.max = max;
  p.minOpen = minOpen;
  p.maxOpen = maxOpen;
  return std::move(p);
}
ParamDecl&& positive(ParamDecl&& p) {
  return range(std::move(p), 0.0, std::numeric_limits<double>::infinity(), true, false);
}
ParamDecl&& nonNegative(ParamDecl&& p) {
  return range(std::move(p), 0.0, std::numeric_limits<double>::infinity(), false, false);
}
ParamDecl&& required(ParamDecl&& p) {
  p.required = true;
  return std::move(p);
}
ParamDecl&& when(ParamDecl&& p, std::string param, std::vector<std::string> values) {
  p.when = ParamCondition{std::move(param), std::move(values)};
  return std::move(p);
}

ParamSet::ParamSet(const std::vector<ParamDecl>& decls) {
  for (const ParamDecl& d : decls) values_[d.name] = d.defaultValue;
}

const ParamValue& ParamSet::get(const std::string& name) const {
  const auto it = values_.find(name);
  if (it == values_.end()) throw InvalidArgument(concat("no parameter named '", name, "'"));
  return it->second;
}
double ParamSet::getFloat(const std::string& name) const { return std::get<double>(get(name)); }
std::int64_t ParamSet::getInt(const std::string& name) const { return std::get<std::int64_t>(get(name)); }
bool ParamSet::getBool(const std::string& name) const { return std::get<bool>(get(name)); }
const std::string& ParamSet::getString(const std::string& name) const { return std::get<std::string>(get(name)); }
const Vec3d& ParamSet::getVec3(const std::string& name) const { return std::get<Vec3d>(get(name)); }
const std::vector<double>& ParamSet::getFloats(const std::string& name) const {
  return std::get<std::vector<double>>(get(name));
}

bool applies(const ParamDecl& decl, const ParamSet& values) {
  if (decl.when.param.empty()) return true;
  const ParamValue& v = values.get(decl.when.param);
  std::string text;
  if (const std::string* s = std::get_if<std::string>(&v))
    text = *s;
  else if (const bool* b = std::get_if<bool>(&v))
    text = *b ? "true" : "false";
  for (const std::string& allowed : decl.when.values)
    if (allowed == text) return true;
  return false;
}

}  // namespace lodestone::plugin
