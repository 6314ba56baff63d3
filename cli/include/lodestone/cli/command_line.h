#pragma once
// Command-line parsing for Lodestone's programs, on CLI11: each option is
// declared once (name, value rule, default, help line) and the usage text is
// generated from the declarations, so help and options cannot drift. What this
// adds to CLI11: value rules whose errors name the option and the bad value in
// the programs' words ("--dx: must be > 0 m, got -1") and whose descriptions
// end the option's help line (HelpFormatter); options read with strtod
// (addNumber, addNumberList); and one ending for --help, --version and bad
// arguments (parse()).
#include <CLI/CLI.hpp>

#include "lodestone/core/base/number_text.h"

#include <climits>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace lodestone::cli {

/// The whole of `text` as a finite number (strtod syntax); nullopt otherwise.
inline std::optional<double> toNumber(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v)) return std::nullopt;
  return v;
}

/// The shortest text that reads back as `v` ("0.5", "1e-6", "300", "1e4"; a
/// whole number as digits unless the exponent form is shorter).
inline std::string formatNumber(double v) {
  std::ostringstream s;
  s.precision(roundTripDigits(v));
  s << v;
  // The exponent without '+' and leading zeros: "1e+04" -> "1e4", "1e-08" -> "1e-8".
  std::string text = s.str();
  const std::size_t e = text.find('e');
  if (e != std::string::npos) {
    std::size_t digits = e + 1;
    if (digits < text.size() && text[digits] == '+')
      text.erase(digits, 1);
    else if (digits < text.size() && text[digits] == '-')
      ++digits;
    while (digits + 1 < text.size() && text[digits] == '0') text.erase(digits, 1);
  }
  if (v == std::floor(v) && std::fabs(v) < 1e15) {
    const std::string whole = std::to_string(static_cast<long long>(v));
    if (whole.size() <= text.size()) return whole;
  }
  return text;
}

/// A value rule: `check` returns the error for a bad text ("" for a good one);
/// the option's name is put in front of it. `description` says what the rule
/// accepts; HelpFormatter puts it at the end of the option's help line
/// (empty: nothing).
inline CLI::Validator rule(std::string description, std::function<std::string(const std::string&)> check) {
  return CLI::Validator([check = std::move(check)](std::string& text) { return check(text); }, std::move(description));
}

/// A finite number: "'abc' is not a number".
inline CLI::Validator number() {
  return rule(
      "", [](const std::string& text) { return toNumber(text) ? std::string() : "'" + text + "' is not a number"; });
}

/// A finite number > `lo` (`unit` after the bound in the error: "must be > 0 m, got -1").
inline CLI::Validator numberAbove(double lo, const std::string& unit = "") {
  return rule("> " + formatNumber(lo) + (unit.empty() ? "" : " " + unit),
              [lo, unit](const std::string& text) -> std::string {
                const std::optional<double> v = toNumber(text);
                if (!v) return "'" + text + "' is not a number";
                if (!(*v > lo))
                  return "must be > " + formatNumber(lo) + (unit.empty() ? "" : " " + unit) + ", got " + text;
                return "";
              });
}

/// A finite number in [lo, hi] (`unit` after the bounds in the error).
inline CLI::Validator numberIn(double lo, double hi, const std::string& unit = "") {
  return rule("in [" + formatNumber(lo) + ", " + formatNumber(hi) + "]" + (unit.empty() ? "" : " " + unit),
              [lo, hi, unit](const std::string& text) -> std::string {
                const std::optional<double> v = toNumber(text);
                if (!v) return "'" + text + "' is not a number";
                if (!(*v >= lo && *v <= hi))
                  return "must be in [" + formatNumber(lo) + ", " + formatNumber(hi) + "]" +
                         (unit.empty() ? "" : " " + unit) + ", got " + text;
                return "";
              });
}

/// A whole number in lo..hi (hi = LLONG_MAX: no upper bound); `what` names
/// what is counted in the error ("must be a whole number of frames in 0..1000000, got 2.5").
inline CLI::Validator wholeNumber(long long lo, long long hi = LLONG_MAX, const std::string& what = "") {
  return rule("a whole number" + (hi == LLONG_MAX ? " >= " + std::to_string(lo)
                                                  : " in " + std::to_string(lo) + ".." + std::to_string(hi)),
              [lo, hi, what](const std::string& text) -> std::string {
                const std::optional<double> v = toNumber(text);
                if (!v) return "'" + text + "' is not a number";
                if (!(*v == std::floor(*v) && *v >= double(lo) && *v <= double(hi)))
                  return "must be a whole number" + (what.empty() ? "" : " of " + what) +
                         (hi == LLONG_MAX ? " >= " + std::to_string(lo)
                                          : " in " + std::to_string(lo) + ".." + std::to_string(hi)) +
                         ", got " + text;
                return "";
              });
}

/// One of `choices`: "'x' is not one of a, b".
inline CLI::Validator oneOf(std::vector<std::string> choices) {
  std::string list;
  for (const std::string& c : choices) list += (list.empty() ? "" : ", ") + c;
  return rule("one of " + list, [choices = std::move(choices), list](const std::string& text) -> std::string {
    for (const std::string& c : choices)
      if (text == c) return "";
    return "'" + text + "' is not one of " + list;
  });
}

/// An option whose text is read as a number into `target` (by strtod, the
/// reading the rules check; an integer target gets the whole number). Give it
/// a rule with ->check(); ->default_str(formatNumber(target)) shows the default.
template <class T>
CLI::Option* addNumber(CLI::App& app, const std::string& name, T& target, const std::string& help) {
  return app.add_option_function<std::string>(
      name, [&target](const std::string& text) { target = static_cast<T>(toNumber(text).value_or(0)); }, help);
}

/// Comma-separated finite numbers ("64,128"); nullopt when an item is not one
/// (numberList() says which).
inline std::optional<std::vector<double>> toNumberList(const std::string& text) {
  std::vector<double> values;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    const std::optional<double> v = toNumber(item);
    if (!v) return std::nullopt;
    values.push_back(*v);
  }
  return values;
}

/// Comma-separated finite numbers: "bad value 'x'" names the first bad item.
inline CLI::Validator numberList() {
  return rule("comma-separated numbers", [](const std::string& text) -> std::string {
    std::stringstream items(text);
    std::string item;
    while (std::getline(items, item, ','))
      if (!toNumber(item)) return "bad value '" + item + "'";
    return "";
  });
}

/// "64,128" for {64, 128}.
inline std::string formatNumberList(const std::vector<double>& values) {
  std::string text;
  for (double v : values) text += (text.empty() ? "" : ",") + formatNumber(v);
  return text;
}

/// An option of comma-separated numbers read into `target`, shown with
/// `target`'s values as the default.
inline CLI::Option* addNumberList(CLI::App& app, const std::string& name, std::vector<double>& target,
                                  const std::string& help) {
  const std::string shown = formatNumberList(target);
  return app
      .add_option_function<std::string>(
          name, [&target](const std::string& text) { target = toNumberList(text).value_or(std::vector<double>{}); },
          help)
      ->type_name("LIST")
      ->check(numberList())
      ->default_str(shown);
}

/// `text` with its lines broken at spaces to at most `width` characters
/// (a longer word stays whole); its own line breaks are kept.
inline std::string wrap(const std::string& text, std::size_t width) {
  std::string out, line, word;
  std::stringstream lines(text);
  bool firstLine = true;
  while (std::getline(lines, line)) {
    if (!firstLine) out += '\n';
    firstLine = false;
    std::stringstream words(line);
    std::size_t used = 0;
    while (words >> word) {
      if (used > 0 && used + 1 + word.size() > width) {
        out += '\n';
        used = 0;
      } else if (used > 0) {
        out += ' ';
        ++used;
      }
      out += word;
      used += word.size();
    }
  }
  return out;
}

/// CLI11's help layout with the value rules said in the help line: an
/// option's name column shows "--threads N=0" (value name, default,
/// REQUIRED) and its help line ends with what its rules accept ("a whole
/// number in 0..1024"), taken from the rules' descriptions, so the help says
/// what the parser checks. Help lines are wrapped to `width` characters.
class HelpFormatter : public CLI::Formatter {
 public:
  HelpFormatter(std::size_t column, std::size_t width) : width_(width) { column_width(column); }

  std::string make_option_opts(const CLI::Option* opt) const override {
    std::string out;
    if (opt->get_type_size() != 0) {
      const std::string type = typeParts(opt).first;
      if (!type.empty()) out += " " + type;
      if (!opt->get_default_str().empty()) out += "=" + opt->get_default_str();
      if (opt->get_required()) out += " " + get_label("REQUIRED");
    }
    return out;
  }

  std::string make_option_desc(const CLI::Option* opt) const override {
    std::string text = opt->get_description();
    const std::string rules = typeParts(opt).second;
    if (!rules.empty()) text += (text.empty() ? "" : "; ") + rules;
    return wrap(text, room());
  }

  std::string make_subcommand(const CLI::App* sub) const override {
    std::stringstream out;
    CLI::detail::format_help(out, sub->get_display_name(true), wrap(sub->get_description(), room()),
                             get_column_width());
    return out.str();
  }

 private:
  std::size_t room() const { return width_ > get_column_width() + 20 ? width_ - get_column_width() : 20; }

  // The value name and the rules' descriptions ("; "-separated), which
  // CLI11's get_type_name() joins with ':'. (get_validator() is not const
  // but only reads.)
  static std::pair<std::string, std::string> typeParts(const CLI::Option* opt) {
    std::string suffix, rules;
    auto* o = const_cast<CLI::Option*>(opt);
    for (int i = 0;; ++i) {
      std::string description;
      try {
        description = o->get_validator(i)->get_description();
      } catch (const CLI::OptionNotFound&) {
        break;
      }
      if (description.empty()) continue;
      suffix += ":" + description;
      rules += (rules.empty() ? "" : "; ") + description;
    }
    std::string type = opt->get_type_name();
    if (type.size() >= suffix.size() && type.compare(type.size() - suffix.size(), suffix.size(), suffix) == 0)
      type.resize(type.size() - suffix.size());
    return {type, rules};
  }

  std::size_t width_;
};

/// The help layout (HelpFormatter: option names in a column `column`
/// characters wide, lines wrapped to `width`) and "-h,--help". Call it before
/// adding subcommands, which take the layout from their parent.
inline void helpLayout(CLI::App& app, std::size_t column = 30, std::size_t width = 100) {
  app.formatter(std::make_shared<HelpFormatter>(column, width));
  app.set_help_flag("-h,--help", "print this help and exit");
}

/// The command line of the deepest (sub)command `app` parsed: "lodestone run".
inline std::string commandPath(const CLI::App& app) {
  std::string path = app.get_name();
  const CLI::App* at = &app;
  while (!at->get_subcommands().empty()) {
    at = at->get_subcommands().front();
    path += " " + at->get_name();
  }
  return path;
}

/// Parses the command line. Returns nullopt to go on, or the code to exit
/// with: 0 after --help or --version (printed on stdout), `errorCode` after a
/// bad argument, with "NAME: MESSAGE (see NAME [COMMAND] --help)" on stderr.
inline std::optional<int> parse(CLI::App& app, int argc, const char* const* argv, int errorCode = 1) {
  try {
    app.parse(argc, argv);
    return std::nullopt;
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string message = e.what();
    // "--dx: 1 required M:> 0 m missing" (CLI11's words, with the rules in
    // the value's name) says: no value after the option.
    const std::size_t colon = message.find(": 1 required ");
    if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) && colon != std::string::npos &&
        message.compare(message.size() - 8, 8, " missing") == 0)
      message = message.substr(0, colon) + " needs a value";
    std::cout.flush();
    std::cerr << app.get_name() << ": " << message << " (see " << commandPath(app) << " --help)" << std::endl;
    return errorCode;
  }
}

}  // namespace lodestone::cli
