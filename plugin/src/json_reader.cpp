#include "lodestone/plugin/json_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <cerrno>
#include <filesystem>
#include <sstream>
#include <utility>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/number_text.h"

namespace lodestone::plugin {
namespace {

using nlohmann::json;

std::string withUnit(const std::string& unit) { return unit.empty() || unit == "1" ? std::string() : " in " + unit; }

std::string lowerCase(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

std::string formatNumber(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", std::max(6, roundTripDigits(v)), v);
  return buf;
}

std::string numberExpectation(const std::string& what, const std::string& unit, const Range& range) {
  std::string s = what + withUnit(unit);
  const std::string r = range.describe();
  if (!r.empty()) s += " " + r;
  return s;
}

std::string quoteList(const std::vector<std::string>& words, const char* conjunction) {
  std::string s;
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (i > 0) s += i + 1 == words.size() ? concat(" ", conjunction, " ") : std::string(", ");
    s += "'" + words[i] + "'";
  }
  return s;
}

std::string arrayOf(std::size_t minCount, std::size_t maxCount, const char* what) {
  std::string count;
  if (maxCount == std::numeric_limits<std::size_t>::max()) {
    if (minCount > 0) count = concat("at least ", minCount, " ");
  } else {
    count = minCount == maxCount ? concat(minCount, " ") : concat(minCount, " to ", maxCount, " ");
  }
  return concat("an array of ", count, what);
}

namespace {

// Tracks the path of the value being parsed, to name duplicate keys.
class DuplicateKeyCheck {
 public:
  explicit DuplicateKeyCheck(std::string source) : source_(std::move(source)) {}

  bool operator()(int /*depth*/, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        enterChild();
        frames_.push_back(Frame{false, 0, {}, {}});
        break;
      case json::parse_event_t::array_start:
        enterChild();
        frames_.push_back(Frame{true, 0, {}, {}});
        break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!frames_.empty()) frames_.pop_back();
        break;
      case json::parse_event_t::key: {
        Frame& top = frames_.back();
        top.key = parsed.get<std::string>();
        if (!top.keys.insert(top.key).second) {
          const std::string where = pathOfTop();
          throw InvalidArgument(concat(source_, ": ", where.empty() ? std::string("top level") : where,
                                       ": duplicate key '", top.key, "'"));
        }
        break;
      }
      case json::parse_event_t::value:
        enterChild();
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool array;
    std::size_t next;  // arrays: index of the next element
    std::string key;   // objects: the last key read
    std::set<std::string> keys;
  };

  void enterChild() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().next;
  }

  // Path of the object on top of the stack (the root is "").
  std::string pathOfTop() const {
    std::string p;
    for (std::size_t i = 0; i + 1 < frames_.size(); ++i) {
      const Frame& f = frames_[i];
      if (f.array)
        p += "[" + std::to_string(f.next - 1) + "]";
      else
        p += (p.empty() ? "" : ".") + f.key;
    }
    return p;
  }

  std::string source_;
  std::vector<Frame> frames_;
};

// nlohmann's message without its "[json.exception...] parse error at ...: " prefix.
std::string parseErrorMessage(const std::string& what) {
  const std::size_t at = what.find("parse error");
  if (at == std::string::npos) return what;
  const std::size_t colon = what.find(": ", at);
  return colon == std::string::npos ? what : what.substr(colon + 2);
}

// "line:column" of a byte offset: 1-based, the column counted in UTF-8
// characters (continuation bytes skipped).
std::string location(const std::string& text, std::size_t offset) {
  std::size_t line = 1, lineStart = 0;
  for (std::size_t i = 0; i < offset; ++i)
    if (text[i] == '\n') {
      ++line;
      lineStart = i + 1;
    }
  // A UTF-8 byte-order mark (skipped by nlohmann) is not a column.
  if (lineStart == 0 && text.compare(0, 3, "\xEF\xBB\xBF") == 0) lineStart = std::min<std::size_t>(3, offset);
  std::size_t column = 1;
  for (std::size_t i = lineStart; i < offset; ++i)
    if ((static_cast<unsigned char>(text[i]) & 0xC0) != 0x80) ++column;
  return concat(line, ":", column);
}

// Without the "[json.exception.out_of_range.406] " prefix.
std::string stripExceptionId(const std::string& what) {
  if (what.rfind("[json.exception.", 0) == 0) {
    const std::size_t end = what.find("] ");
    if (end != std::string::npos) return what.substr(end + 2);
  }
  return what;
}

bool isNumberChar(char c) { return (c >= '0' && c <= '9') || c == '.' || c == 'e' || c == 'E' || c == '+' || c == '-'; }

// Offset of the first occurrence of `token` not embedded in a longer number
// (outside strings is not checked: good enough to point at the culprit).
std::size_t findNumberToken(const std::string& text, const std::string& token) {
  for (std::size_t at = text.find(token); at != std::string::npos; at = text.find(token, at + 1)) {
    const bool before = at == 0 || !isNumberChar(text[at - 1]);
    const bool after = at + token.size() >= text.size() || !isNumberChar(text[at + token.size()]);
    if (before && after) return at;
  }
  return std::string::npos;
}

}  // namespace

// ---------------------------------------------------------------- parsing

nlohmann::json parseJsonText(const std::string& text, const std::string& sourceName) {
  DuplicateKeyCheck check(sourceName);
  try {
    return json::parse(text, json::parser_callback_t(std::ref(check)), /*allow_exceptions=*/true,
                       /*ignore_comments=*/false);
  } catch (const json::parse_error& e) {
    // e.byte: 1-based index of the last character read (text.size() + 1 at
    // the end of the input).
    const std::size_t offset = std::min<std::size_t>(e.byte > 0 ? e.byte - 1 : 0, text.size());
    throw InvalidArgument(concat(sourceName, ":", location(text, offset), ": ", parseErrorMessage(e.what())));
  } catch (const json::out_of_range& e) {
    // A number beyond double range (1e999): nlohmann names the token but not
    // its position; locate the first standalone occurrence of the token.
    const std::string message = stripExceptionId(e.what());
    const std::size_t open = message.find('\''), close = message.rfind('\'');
    if (open != std::string::npos && close > open + 1) {
      const std::size_t at = findNumberToken(text, message.substr(open + 1, close - open - 1));
      if (at != std::string::npos) throw InvalidArgument(concat(sourceName, ":", location(text, at), ": ", message));
    }
    throw InvalidArgument(concat(sourceName, ": ", message));
  } catch (const json::exception& e) {
    throw InvalidArgument(concat(sourceName, ": ", stripExceptionId(e.what())));
  }
}

std::string readJsonFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InvalidArgument(concat("'", path, "' is a directory, not a JSON file"));
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InvalidArgument(concat("cannot open the JSON file '", path, "' (", std::strerror(errno), ")"));
  std::string text;
  char buf[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
    if (text.size() + n > kMaxJsonFileBytes) {
      std::fclose(f);
      throw InvalidArgument(concat("the JSON file '", path, "' is larger than ", kMaxJsonFileBytes >> 20,
                                   " MiB (not a scene or parameter file?)"));
    }
    text.append(buf, n);
  }
  const bool failed = std::ferror(f) != 0;
  const int error = errno;
  std::fclose(f);
  if (failed) throw InvalidArgument(concat("cannot read the JSON file '", path, "' (", std::strerror(error), ")"));
  return text;
}

nlohmann::json parseJsonFile(const std::string& path) { return parseJsonText(readJsonFile(path), path); }

// ---------------------------------------------------------------- helpers

bool Range::contains(double v) const {
  if (std::isnan(v)) return false;
  if (minOpen ? !(v > min) : !(v >= min)) return false;
  if (maxOpen ? !(v < max) : !(v <= max)) return false;
  return true;
}

std::string Range::describe() const {
  const bool lo = std::isfinite(min), hi = std::isfinite(max);
  if (lo && hi)
    return concat("in ", minOpen ? "(" : "[", formatNumber(min), ", ", formatNumber(max), maxOpen ? ")" : "]");
  if (lo) return concat(minOpen ? "> " : ">= ", formatNumber(min));
  if (hi) return concat(maxOpen ? "< " : "<= ", formatNumber(max));
  return "";
}

int editDistance(const std::string& a, const std::string& b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1, 0));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = int(i);
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = int(j);
  for (std::size_t i = 1; i <= n; ++i)
    for (std::size_t j = 1; j <= m; ++j) {
      const int cost = a[i - 1] == b[j - 1] ? 0 : 1;
      int v = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) v = std::min(v, d[i - 2][j - 2] + 1);
      d[i][j] = v;
    }
  return d[n][m];
}

std::string closestMatch(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  int bestDistance = std::numeric_limits<int>::max();
  for (const std::string& c : candidates) {
    if (c == word) continue;
    const int dist = lowerCase(c) == lowerCase(word) ? 0 : editDistance(word, c);
    const int allowed = std::max<int>(1, int(std::max(word.size(), c.size())) / 3);
    // dist < the shorter length: "x" is not a typo of "y".
    if (dist <= allowed && dist < int(std::min(word.size(), c.size())) && dist < bestDistance) {
      best = c;
      bestDistance = dist;
    }
  }
  return best;
}

std::string didYouMean(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string guess = closestMatch(word, candidates);
  return guess.empty() ? std::string() : "; did you mean '" + guess + "'?";
}

std::string jsonTypeName(const nlohmann::json& value) {
  if (value.is_number()) return "number";
  return value.type_name();
}

std::string describeJsonValue(const nlohmann::json& value) {
  if (value.is_object()) return value.empty() ? "an empty object" : concat("an object with ", value.size(), " keys");
  if (value.is_array())
    return value.empty() ? "an empty array"
                         : concat("an array of ", value.size(), value.size() == 1 ? " element" : " elements");
  if (value.is_null()) return "null";
  if (value.is_number_float()) return "number " + formatNumber(value.get<double>());
  std::string text = value.dump();
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return jsonTypeName(value) + " " + text;
}

// ---------------------------------------------------------------- JsonReader

JsonReader::JsonReader(const nlohmann::json& value, std::string path, std::string file)
    : value_(&value), path_(std::move(path)), file_(std::move(file)) {
  if (!value.is_object()) failPath(path_, concat("expected an object, found ", describeJsonValue(value)));
}

std::string JsonReader::pathOf(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

void JsonReader::failPath(const std::string& where, const std::string& message) const {
  throw InvalidArgument(concat(file_, ": ", where.empty() ? std::string("top level") : where, ": ", message));
}

void JsonReader::fail(const std::string& message) const { failPath(path_, message); }

void JsonReader::failAt(const std::string& key, const std::string& message) const { failPath(pathOf(key), message); }

bool JsonReader::has(const std::string& key) {
  known_.insert(key);
  return value_->contains(key);
}

const nlohmann::json* JsonReader::find(const std::string& key) {
  known_.insert(key);
  const auto it = value_->find(key);
  if (it == value_->end()) return nullptr;
  read_.insert(key);
  return &*it;
}

const nlohmann::json& JsonReader::require(const std::string& key, const std::string& expected) {
  const nlohmann::json* v = find(key);
  if (v == nullptr) {
    // A misspelt key is the usual cause: name the present key it resembles.
    std::vector<std::string> present;
    for (auto it = value_->begin(); it != value_->end(); ++it)
      if (!known_.count(it.key())) present.push_back(it.key());
    const std::string guess = closestMatch(key, present);
    fail(concat("missing required key '", key, "' (", expected, ")",
                guess.empty() ? std::string() : concat("; did you mean '", key, "' instead of '", guess, "'?")));
  }
  return *v;
}

double JsonReader::toNumber(const nlohmann::json& v, const std::string& where, const std::string& unit,
                            const Range& range) const {
  const std::string expected = numberExpectation("a number", unit, range);
  if (!v.is_number()) failPath(where, concat("expected ", expected, ", found ", describeJsonValue(v)));
  const double x = v.get<double>();
  if (!std::isfinite(x))
    failPath(where, concat("expected ", expected, ", found a non-finite number (", formatNumber(x), ")"));
  if (!range.contains(x)) failPath(where, concat("expected ", expected, ", found ", describeJsonValue(v)));
  return x;
}

std::int64_t JsonReader::toInteger(const nlohmann::json& v, const std::string& where, std::int64_t min,
                                   std::int64_t max) const {
  const std::string expected = concat("an integer in [", min, ", ", max, "]");
  if (v.is_number_integer()) {
    bool ok;
    std::int64_t x = 0;
    if (v.is_number_unsigned()) {
      const std::uint64_t u = v.get<std::uint64_t>();
      ok = u <= std::uint64_t(std::numeric_limits<std::int64_t>::max());
      x = ok ? std::int64_t(u) : 0;
    } else {
      x = v.get<std::int64_t>();
      ok = true;
    }
    if (ok && x >= min && x <= max) return x;
    failPath(where, concat("expected ", expected, ", found ", describeJsonValue(v)));
  }
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (!std::isfinite(d))
      failPath(where, concat("expected ", expected, ", found a non-finite number (", formatNumber(d), ")"));
    if (d != std::floor(d))
      failPath(where, concat("expected ", expected, ", found the non-integer ", describeJsonValue(v)));
    // Compare as doubles first: int64 bounds are not all representable.
    if (d >= double(min) && d <= double(max)) {
      const auto x = std::int64_t(d);
      if (x >= min && x <= max) return x;
    }
    failPath(where, concat("expected ", expected, ", found ", describeJsonValue(v)));
  }
  failPath(where, concat("expected ", expected, ", found ", describeJsonValue(v)));
}

double JsonReader::number(const std::string& key, const std::string& unit, const Range& range) {
  return toNumber(require(key, numberExpectation("a number", unit, range)), pathOf(key), unit, range);
}

double JsonReader::number(const std::string& key, const std::string& unit, const Range& range, double fallback) {
  const nlohmann::json* v = find(key);
  return v == nullptr ? fallback : toNumber(*v, pathOf(key), unit, range);
}

double JsonReader::number(const std::string& key, const std::string& unit, double min, double max) {
  return number(key, unit, Range::closed(min, max));
}

double JsonReader::number(const std::string& key, const std::string& unit, double min, double max, double fallback) {
  return number(key, unit, Range::closed(min, max), fallback);
}

int JsonReader::integer(const std::string& key, int min, int max) { return int(integer64(key, min, max)); }

int JsonReader::integer(const std::string& key, int min, int max, int fallback) {
  return int(integer64(key, min, max, fallback));
}

std::int64_t JsonReader::integer64(const std::string& key, std::int64_t min, std::int64_t max) {
  return toInteger(require(key, concat("an integer in [", min, ", ", max, "]")), pathOf(key), min, max);
}

std::int64_t JsonReader::integer64(const std::string& key, std::int64_t min, std::int64_t max, std::int64_t fallback) {
  const nlohmann::json* v = find(key);
  return v == nullptr ? fallback : toInteger(*v, pathOf(key), min, max);
}

bool JsonReader::boolean(const std::string& key) {
  const nlohmann::json& v = require(key, "true or false");
  if (!v.is_boolean()) failAt(key, concat("expected true or false, found ", describeJsonValue(v)));
  return v.get<bool>();
}

bool JsonReader::boolean(const std::string& key, bool fallback) { return has(key) ? boolean(key) : fallback; }

std::string JsonReader::toString(const nlohmann::json& v, const std::string& key,
                                 const std::vector<std::string>& allowed) const {
  const std::string expected = allowed.empty() ? std::string("a string") : "one of " + quoteList(allowed);
  if (!v.is_string()) failAt(key, concat("expected ", expected, ", found ", describeJsonValue(v)));
  std::string s = v.get<std::string>();
  if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), s) == allowed.end())
    failAt(key, concat("expected ", expected, ", found '", s, "'", didYouMean(s, allowed)));
  return s;
}

std::string JsonReader::string(const std::string& key, const std::vector<std::string>& allowed) {
  const std::string expected = allowed.empty() ? std::string("a string") : "one of " + quoteList(allowed);
  return toString(require(key, expected), key, allowed);
}

std::string JsonReader::string(const std::string& key, const std::vector<std::string>& allowed,
                               const std::string& fallback) {
  const nlohmann::json* v = find(key);
  return v == nullptr ? fallback : toString(*v, key, allowed);
}

Vec3d JsonReader::toVec3(const nlohmann::json& v, const std::string& key, const std::string& unit,
                         const Range& range) const {
  if (!v.is_array() || v.size() != 3)
    failAt(key, concat("expected ", numberExpectation("an array of 3 numbers [x, y, z]", unit, range), ", found ",
                       describeJsonValue(v)));
  Vec3d r;
  for (int i = 0; i < 3; ++i) r[i] = toNumber(v[std::size_t(i)], concat(pathOf(key), "[", i, "]"), unit, range);
  return r;
}

Vec3d JsonReader::vec3(const std::string& key, const std::string& unit, const Range& componentRange) {
  return toVec3(require(key, numberExpectation("an array of 3 numbers [x, y, z]", unit, componentRange)), key, unit,
                componentRange);
}

Vec3d JsonReader::vec3(const std::string& key, const std::string& unit, const Range& componentRange,
                       const Vec3d& fallback) {
  const nlohmann::json* v = find(key);
  return v == nullptr ? fallback : toVec3(*v, key, unit, componentRange);
}

Vec3d JsonReader::nonZeroVec3(const std::string& key) {
  const Vec3d d = vec3(key, "");
  const double n = norm(d);
  if (!(n > 0) || !std::isfinite(n)) failAt(key, "expected a non-zero direction vector [x, y, z], found [0, 0, 0]");
  return d;
}

Vec3d JsonReader::direction(const std::string& key) {
  const Vec3d d = nonZeroVec3(key);
  return d / norm(d);
}

Vec3d JsonReader::direction(const std::string& key, const Vec3d& fallback) {
  return has(key) ? direction(key) : fallback;
}

std::vector<double> JsonReader::numbers(const std::string& key, const std::string& unit, const Range& range,
                                        std::size_t minCount, std::size_t maxCount) {
  const std::string expected = numberExpectation(arrayOf(minCount, maxCount, "numbers"), unit, range);
  const nlohmann::json& v = require(key, expected);
  if (!v.is_array() || v.size() < minCount || v.size() > maxCount)
    failAt(key, concat("expected ", expected, ", found ", describeJsonValue(v)));
  std::vector<double> r;
  r.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) r.push_back(toNumber(v[i], concat(pathOf(key), "[", i, "]"), unit, range));
  return r;
}

JsonReader JsonReader::object(const std::string& key) {
  const nlohmann::json& v = require(key, "an object");
  return JsonReader(v, pathOf(key), file_);
}

std::vector<JsonReader> JsonReader::array(const std::string& key, std::size_t minCount, std::size_t maxCount) {
  const std::string expected = arrayOf(minCount, maxCount, "objects");
  const nlohmann::json& v = require(key, expected);
  if (!v.is_array() || v.size() < minCount || v.size() > maxCount)
    failAt(key, concat("expected ", expected, ", found ", describeJsonValue(v)));
  std::vector<JsonReader> r;
  r.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) r.emplace_back(v[i], concat(pathOf(key), "[", i, "]"), file_);
  return r;
}

const nlohmann::json& JsonReader::raw(const std::string& key) { return require(key, "a value"); }

void JsonReader::ignore(const std::string& key) { (void)find(key); }

void JsonReader::finish() const {
  std::vector<std::string> unknown;
  for (auto it = value_->begin(); it != value_->end(); ++it)
    if (read_.count(it.key()) == 0) unknown.push_back(it.key());
  if (unknown.empty()) return;
  // Suggest among the keys asked about that are not in the document already.
  std::vector<std::string> candidates;
  for (const std::string& k : known_)
    if (!value_->contains(k)) candidates.push_back(k);
  const std::string guess = closestMatch(unknown.front(), candidates);
  std::string message = concat("unknown key '", unknown.front(), "'");
  if (!guess.empty()) {
    message += "; did you mean '" + guess + "'?";
  } else {
    std::vector<std::string> known;
    for (const std::string& k : known_)
      if (std::find(unknown.begin(), unknown.end(), k) == unknown.end()) known.push_back(k);
    if (!known.empty()) message += " (known keys: " + quoteList(known, "and") + ")";
  }
  if (unknown.size() > 1) {
    std::vector<std::string> rest(unknown.begin() + 1, unknown.end());
    message += concat(" (and ", rest.size(), " more: ", quoteList(rest, "and"), ")");
  }
  fail(message);
}

}  // namespace lodestone::plugin
