#pragma once
// Strict reading of JSON: the one reader behind scene files (scene.h), node
// parameters given as JSON (param_json.h, the C ABI's network_set_json) and
// the `lodestone` program's own JSON files.
//
// Parsing: parseJsonFile / parseJsonText use nlohmann::json and turn its parse
// errors into lodestone::InvalidArgument "file:line:column: message" (line
// and column 1-based, the column counted in UTF-8 characters, computed from
// the byte offset nlohmann reports). Duplicate keys in one object, which
// nlohmann would silently collapse to the last one, are rejected too, naming
// the object's path. Comments are not JSON and are rejected.
//
// Validation: a JsonReader wraps one JSON object together with its path in
// the document ("bodies[2].material") and the file name. Each accessor reads
// one key, checks its type, unit-carrying range or allowed values, and throws
// lodestone::InvalidArgument saying where, what was expected and what was
// found, e.g.
//   scene.json: bodies[2].material.density: expected a number in kg/m^3 > 0, found number -5
//   scene.json: bodies[2].material: missing required key 'density' (a number in kg/m^3 > 0)
// Non-finite numbers are always rejected (parsing already refuses 1e999; a
// document built in code may hold inf or NaN). A key set to null is a type
// error, not an absent key. finish() rejects every key that no accessor read,
// with a suggestion from the keys the reader was asked about
// (optimal-string-alignment edit distance):
//   scene.json: bodies[2].material: unknown key 'densty'; did you mean 'density'?
// Typical use:
//   const nlohmann::json doc = parseJsonFile(path);
//   JsonReader scene(doc, "", path);
//   const double dt = scene.number("dt", "s", Range::above(0), 1e-4);   // optional
//   for (JsonReader& body : scene.array("bodies")) {
//     JsonReader material = body.object("material");
//     const double rho = material.number("density", "kg/m^3", Range::above(0));  // required
//     material.finish();
//     body.finish();
//   }
//   scene.finish();
// The reader refers to the document: keep the nlohmann::json alive while it is
// used.
#include <cstdint>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lodestone/core/base/vec3.h"

namespace lodestone::plugin {

/// Parses JSON text. `sourceName` (a file name) prefixes error messages.
/// Throws lodestone::InvalidArgument "sourceName:line:column: message" on a
/// syntax error and "sourceName: path: duplicate key 'k'" on a repeated key.
nlohmann::json parseJsonText(const std::string& text, const std::string& sourceName);

/// The largest JSON file readJsonFile reads: 64 MiB.
inline constexpr std::size_t kMaxJsonFileBytes = std::size_t(64) << 20;

/// The text of a JSON file, read whole. Throws lodestone::InvalidArgument
/// naming `path` when it cannot be opened or read, is a directory, or holds
/// more than kMaxJsonFileBytes (a device such as /dev/zero stops there).
std::string readJsonFile(const std::string& path);

/// Reads (readJsonFile) and parses a file (see parseJsonText).
nlohmann::json parseJsonFile(const std::string& path);

/// An interval of accepted numbers, each end open or closed (or infinite).
struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool minOpen = false;  ///< min itself excluded
  bool maxOpen = false;  ///< max itself excluded

  static Range any() { return {}; }
  static Range closed(double lo, double hi) { return {lo, hi, false, false}; }  ///< [lo, hi]
  static Range atLeast(double lo) { return {lo, std::numeric_limits<double>::infinity(), false, false}; }
  static Range above(double lo) { return {lo, std::numeric_limits<double>::infinity(), true, false}; }
  static Range atMost(double hi) { return {-std::numeric_limits<double>::infinity(), hi, false, false}; }
  static Range below(double hi) { return {-std::numeric_limits<double>::infinity(), hi, false, true}; }
  static Range positive() { return above(0.0); }       ///< > 0
  static Range nonNegative() { return atLeast(0.0); }  ///< >= 0

  bool contains(double v) const;
  /// "> 0", ">= 1", "<= 2", "in [0, 1]", "in (0, 1]", "" for any().
  std::string describe() const;
};

/// Optimal-string-alignment distance (insertions, deletions, substitutions
/// and swaps of adjacent characters each cost 1).
int editDistance(const std::string& a, const std::string& b);

/// The candidate closest to `word` when close enough to be a likely typo
/// (distance <= max(1, longer length / 3) and below the shorter length, or
/// equal ignoring case); "" otherwise. The one suggestion of every "did you
/// mean" message: scene keys and values, node types, nodes, parameters and
/// ports of a network.
std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates);
/// "; did you mean 'x'?" for closestMatch's answer, "" when there is none.
std::string didYouMean(const std::string& word, const std::vector<std::string>& candidates);

// The words of every "expected ..., found ..." message, shared by the reader
// and ParamDecl::check (a value set on a network node).

/// Shortest "%g" text that reads back as the same double ("nan", "inf").
std::string formatNumber(double v);
/// "a number in kg/m^3 > 0": `what`, the unit (none when "" or "1") and the range.
std::string numberExpectation(const std::string& what, const std::string& unit, const Range& range);
/// "'a', 'b' or 'c'" (`conjunction` "or" or "and").
std::string quoteList(const std::vector<std::string>& words, const char* conjunction = "or");
/// "an array of [at least N | N | N to M] <what>".
std::string arrayOf(std::size_t minCount, std::size_t maxCount, const char* what);

/// "object", "array", "string", "boolean", "number", "null"...
std::string jsonTypeName(const nlohmann::json& value);
/// A short description of a found value: `number -5`, `string "abc"`,
/// `an object`, `an array of 3 elements`; long text is cut with "...".
std::string describeJsonValue(const nlohmann::json& value);

/// Validating view of one JSON object (see the file comment).
class JsonReader {
 public:
  /// `value` must be an object (else InvalidArgument naming the path);
  /// `path` is its location ("" for the document root), `file` the source.
  JsonReader(const nlohmann::json& value, std::string path, std::string file);

  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  const nlohmann::json& json() const { return *value_; }
  /// Path of a key of this object: "bodies[2].material.density".
  std::string pathOf(const std::string& key) const;

  /// Whether the key is present (any type). Records `key` as known (for the
  /// suggestions of finish()) but not as read.
  bool has(const std::string& key);

  /// Numbers with a unit ("m", "kg/m^3", "" for dimensionless), finite and in
  /// `range`. Required, or optional with a fallback (not checked).
  double number(const std::string& key, const std::string& unit, const Range& range);
  double number(const std::string& key, const std::string& unit, const Range& range, double fallback);
  /// Shorthands for a closed range [min, max].
  double number(const std::string& key, const std::string& unit, double min, double max);
  double number(const std::string& key, const std::string& unit, double min, double max, double fallback);

  /// Integers in [min, max]. A number with an integral value written as a
  /// float (1e5, 3.0) is accepted; 2.5 is not.
  int integer(const std::string& key, int min, int max);
  int integer(const std::string& key, int min, int max, int fallback);
  std::int64_t integer64(const std::string& key, std::int64_t min, std::int64_t max);
  std::int64_t integer64(const std::string& key, std::int64_t min, std::int64_t max, std::int64_t fallback);

  bool boolean(const std::string& key);
  bool boolean(const std::string& key, bool fallback);

  /// A string, one of `allowed` unless that is empty (then any string).
  std::string string(const std::string& key, const std::vector<std::string>& allowed = {});
  std::string string(const std::string& key, const std::vector<std::string>& allowed, const std::string& fallback);

  /// A 3-element array of numbers, each finite and in `componentRange`.
  Vec3d vec3(const std::string& key, const std::string& unit, const Range& componentRange = Range::any());
  Vec3d vec3(const std::string& key, const std::string& unit, const Range& componentRange, const Vec3d& fallback);
  /// A non-zero 3-vector (any length), returned as given.
  Vec3d nonZeroVec3(const std::string& key);
  /// A non-zero 3-vector (any length), returned normalised.
  Vec3d direction(const std::string& key);
  Vec3d direction(const std::string& key, const Vec3d& fallback);

  /// An array of numbers with a unit, each in `range`, with minCount..maxCount elements.
  std::vector<double> numbers(const std::string& key, const std::string& unit, const Range& range = Range::any(),
                              std::size_t minCount = 0, std::size_t maxCount = std::numeric_limits<std::size_t>::max());

  /// A nested object (required).
  JsonReader object(const std::string& key);
  /// An array of objects (required), each element a reader with path "key[i]".
  std::vector<JsonReader> array(const std::string& key, std::size_t minCount = 0,
                                std::size_t maxCount = std::numeric_limits<std::size_t>::max());
  /// The raw value of a present key (marked as read), for custom checks;
  /// throws when the key is missing.
  const nlohmann::json& raw(const std::string& key);
  /// Marks a key as read without checking it (e.g. "comment" entries).
  void ignore(const std::string& key);

  /// Throws for the first key (in key order) that no accessor read, naming it,
  /// suggesting the closest known key, and counting the other unknown keys.
  void finish() const;

  /// Throws InvalidArgument "file: path: message" for this object.
  [[noreturn]] void fail(const std::string& message) const;
  /// Throws InvalidArgument "file: path.key: message".
  [[noreturn]] void failAt(const std::string& key, const std::string& message) const;

 private:
  // The value of `key`, or null when absent (the key is recorded as known and
  // read either way); `expected` describes it for the missing-key error.
  const nlohmann::json* find(const std::string& key);
  const nlohmann::json& require(const std::string& key, const std::string& expected);
  double toNumber(const nlohmann::json& v, const std::string& where, const std::string& unit, const Range& range) const;
  std::int64_t toInteger(const nlohmann::json& v, const std::string& where, std::int64_t min, std::int64_t max) const;
  Vec3d toVec3(const nlohmann::json& v, const std::string& key, const std::string& unit, const Range& range) const;
  std::string toString(const nlohmann::json& v, const std::string& key, const std::vector<std::string>& allowed) const;
  [[noreturn]] void failPath(const std::string& where, const std::string& message) const;

  const nlohmann::json* value_;
  std::string path_, file_;
  std::set<std::string> known_;  // keys asked about
  std::set<std::string> read_;   // keys consumed
};

}  // namespace lodestone::plugin
