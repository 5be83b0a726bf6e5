#include "cli/options.h"

#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstring>
#include <system_error>

#include "cli/commands.h"

namespace skyloc::cli {
namespace {

bool ParseWhole(const char* text, std::int64_t* out) {
  const char* end = text + std::strlen(text);
  const auto [p, ec] = std::from_chars(text, end, *out);
  return ec == std::errc() && p == end && end != text;
}

bool ParseReal(const char* text, double* out) {
  const char* end = text + std::strlen(text);
  const auto [p, ec] = std::from_chars(text, end, *out);
  return ec == std::errc() && p == end && end != text && std::isfinite(*out);
}

std::string WholeRange(std::int64_t min, std::int64_t max) {
  char text[96];
  if (max == std::numeric_limits<std::int64_t>::max())
    std::snprintf(text, sizeof text, "a whole number >= %" PRId64, min);
  else
    std::snprintf(text, sizeof text, "a whole number in %" PRId64 "..%" PRId64, min, max);
  return text;
}

std::string RealRange(const NumberRange& r) {
  char text[128];
  const bool low = std::isfinite(r.min), high = std::isfinite(r.max);
  if (low && high)
    std::snprintf(text, sizeof text, "a number in %c%g, %g%c", r.min_open ? '(' : '[', r.min, r.max,
                  r.max_open ? ')' : ']');
  else if (low)
    std::snprintf(text, sizeof text, "a number %s %g", r.min_open ? ">" : ">=", r.min);
  else if (high)
    std::snprintf(text, sizeof text, "a number %s %g", r.max_open ? "<" : "<=", r.max);
  else
    std::snprintf(text, sizeof text, "a number");
  return text;
}

bool InRange(double v, const NumberRange& r) {
  const bool above = r.min_open ? v > r.min : v >= r.min;
  const bool below = r.max_open ? v < r.max : v <= r.max;
  return above && below;
}

}  // namespace

int ExitCode(ParseOutcome outcome) {
  return outcome == ParseOutcome::kRefused ? kExitUsage : kExitOk;
}

OptionTable::OptionTable(const char* command, const char* synopsis, const char* description)
    : command_(command), synopsis_(synopsis), description_(description) {}

void OptionTable::Add(Option option) {
  options_.push_back(std::move(option));
}

void OptionTable::Flag(const char* name, const char* help, bool* out) {
  Add({name, "", help, false, false, [out](const char*, std::string*) {
         *out = true;
         return true;
       }});
}

void OptionTable::Text(const char* name, const char* value, const char* help, std::string* out) {
  Add({name, value, help, false, false, [out](const char* text, std::string* expected) {
         if (*text == '\0') {
           *expected = "a value that is not empty";
           return false;
         }
         *out = text;
         return true;
       }});
}

void OptionTable::TextList(const char* name, const char* value, const char* help,
                           std::vector<std::string>* out) {
  Add({name, value, help, true, false, [out](const char* text, std::string* expected) {
         if (*text == '\0') {
           *expected = "a value that is not empty";
           return false;
         }
         out->emplace_back(text);
         return true;
       }});
}

namespace {

// The parser of a whole number in [min, max] clipped to T's range, handing the value to
// `take`: the one parser of both Int()s and IntList().
template <typename T, typename Take>
auto WholeParser(std::int64_t min, std::int64_t max, Take take) {
  const std::int64_t lo = std::max<std::int64_t>(min, std::numeric_limits<T>::min());
  const std::int64_t hi = std::min<std::int64_t>(max, std::numeric_limits<T>::max());
  return [=](const char* text, std::string* expected) {
    std::int64_t v = 0;
    if (!ParseWhole(text, &v) || v < lo || v > hi) {
      *expected = WholeRange(lo, hi);
      return false;
    }
    take(static_cast<T>(v));
    return true;
  };
}

}  // namespace

void OptionTable::Int(const char* name, const char* value, const char* help, std::int64_t min,
                      std::int64_t max, std::int64_t* out) {
  Add({name, value, help, false, false,
       WholeParser<std::int64_t>(min, max, [out](std::int64_t v) { *out = v; })});
}

void OptionTable::Int(const char* name, const char* value, const char* help, std::int64_t min,
                      std::int64_t max, int* out) {
  Add({name, value, help, false, false, WholeParser<int>(min, max, [out](int v) { *out = v; })});
}

void OptionTable::Int(const char* name, const char* value, const char* help, std::int64_t min,
                      std::int64_t max, std::optional<int>* out) {
  Add({name, value, help, false, false, WholeParser<int>(min, max, [out](int v) { *out = v; })});
}

void OptionTable::Count(const char* name, const char* value, const char* help, std::uint64_t* out) {
  Add({name, value, help, false, false, [out](const char* text, std::string* expected) {
         std::uint64_t v = 0;
         const char* end = text + std::strlen(text);
         const auto [p, ec] = std::from_chars(text, end, v);
         if (ec != std::errc() || p != end || end == text) {
           *expected = "a whole number >= 0";
           return false;
         }
         *out = v;
         return true;
       }});
}

void OptionTable::IntList(const char* name, const char* value, const char* help, std::int64_t min,
                          std::int64_t max, std::vector<int>* out) {
  Add({name, value, help, true, false,
       WholeParser<int>(min, max, [out](int v) { out->push_back(v); })});
}

void OptionTable::Number(const char* name, const char* value, const char* help, NumberRange range,
                         double* out) {
  AddNumber(name, value, help, range, [out](double v) { *out = v; });
}

void OptionTable::Number(const char* name, const char* value, const char* help, NumberRange range,
                         std::optional<double>* out) {
  AddNumber(name, value, help, range, [out](double v) { *out = v; });
}

void OptionTable::AddNumber(const char* name, const char* value, const char* help,
                            NumberRange range, std::function<void(double)> store) {
  Add({name, value, help, false, false,
       [range, store = std::move(store)](const char* text, std::string* expected) {
         double v = 0;
         if (!ParseReal(text, &v) || !InRange(v, range)) {
           *expected = RealRange(range);
           return false;
         }
         store(v);
         return true;
       }});
}

void OptionTable::NumberPair(const char* name, const char* value, const char* help,
                             const char* expected, std::function<bool(double a, double b)> accept,
                             double* a, double* b) {
  Add({name, value, help, false, false,
       [expected, accept = std::move(accept), a, b](const char* text, std::string* why) {
         const char* comma = std::strchr(text, ',');
         double first = 0, second = 0;
         if (comma == nullptr || !ParseReal(std::string(text, comma).c_str(), &first) ||
             !ParseReal(comma + 1, &second) || !accept(first, second)) {
           *why = expected;
           return false;
         }
         *a = first;
         *b = second;
         return true;
       }});
}

void OptionTable::AddChoice(const char* name, const char* help, std::vector<std::string> names,
                            bool repeatable, std::function<void(std::size_t)> pick) {
  std::string value;
  for (std::size_t i = 0; i < names.size(); ++i)
    value += (i == 0 ? "" : "|") + names[i];
  Add({name, value, help, repeatable, false,
       [names, pick](const char* text, std::string* expected) {
         for (std::size_t i = 0; i < names.size(); ++i) {
           if (names[i] == text) {
             pick(i);
             return true;
           }
         }
         *expected = "";
         for (std::size_t i = 0; i < names.size(); ++i)
           *expected += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
         return false;
       }});
}

void OptionTable::Custom(const char* name, const char* value, const char* help,
                         std::function<bool(const char* text, std::string* expected)> parse) {
  Add({name, value, help, false, false, std::move(parse)});
}

void OptionTable::Positional(const char* value, const char* help, std::size_t min, std::size_t max,
                             std::vector<std::string>* out) {
  positional_ = PositionalSpec{value, help, min, max, out};
}

OptionTable::Option* OptionTable::Find(std::string_view name) {
  for (Option& o : options_)
    if (o.name == name)
      return &o;
  return nullptr;
}

const OptionTable::Option* OptionTable::Find(std::string_view name) const {
  for (const Option& o : options_)
    if (o.name == name)
      return &o;
  return nullptr;
}

bool OptionTable::Given(std::string_view name) const {
  const Option* o = Find(name);
  return o != nullptr && o->given;
}

ParseOutcome OptionTable::Refuse(std::string_view what) const {
  std::fprintf(stderr, "skyloc %s: %.*s\nRun 'skyloc %s --help' for the options.\n", command_,
               static_cast<int>(what.size()), what.data(), command_);
  return ParseOutcome::kRefused;
}

ParseOutcome OptionTable::Parse(std::span<char* const> args) {
  for (char* const a : args) {
    if (IsHelpFlag(a)) {
      PrintHelp(stdout);
      return ParseOutcome::kHelpPrinted;
    }
  }
  std::vector<std::string> words;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const char* a = args[i];
    if (a[0] != '-' || a[1] == '\0') {
      words.emplace_back(a);
      continue;
    }
    Option* o = Find(a);
    if (o == nullptr) {
      return Refuse(std::string("unknown option '") + a + "'");
    }
    if (o->given && !o->repeatable) {
      return Refuse(std::string(a) + " is given twice");
    }
    o->given = true;
    const char* text = "";
    if (!o->value.empty()) {
      if (i + 1 >= args.size()) {
        return Refuse(std::string(a) + " needs a value: " + o->value);
      }
      text = args[++i];
    }
    std::string expected;
    if (!o->store(text, &expected)) {
      return Refuse(std::string(a) + " '" + text + "': expected " + expected + " (" + o->help +
                    ")");
    }
  }
  const PositionalSpec* spec = positional_ ? &*positional_ : nullptr;
  const std::size_t min = spec != nullptr ? spec->min : 0;
  const std::size_t max = spec != nullptr ? spec->max : 0;
  if (words.size() > max) {
    return Refuse(spec == nullptr ? "unexpected argument '" + words[max] + "'"
                                  : "unexpected argument '" + words[max] + "' (at most " +
                                        std::to_string(max) + " " + spec->value + ")");
  }
  if (words.size() < min) {
    return Refuse("missing " + spec->value + " (" + spec->help + ")");
  }
  if (spec != nullptr)
    *spec->out = std::move(words);
  return ParseOutcome::kRun;
}

void OptionTable::PrintHelp(std::FILE* out) const {
  std::fprintf(out, "usage: skyloc %s %s\n", command_, synopsis_);
  if (description_ != nullptr && *description_ != '\0')
    std::fprintf(out, "\n%s", description_);
  if (positional_ || !options_.empty())
    std::fprintf(out, "\n");
  if (positional_)
    std::fprintf(out, "  %-24s %s\n", positional_->value.c_str(), positional_->help.c_str());
  for (const Option& o : options_) {
    const std::string head = o.value.empty() ? o.name : o.name + " " + o.value;
    if (head.size() <= 24)
      std::fprintf(out, "  %-24s %s\n", head.c_str(), o.help.c_str());
    else
      std::fprintf(out, "  %s\n  %-24s %s\n", head.c_str(), "", o.help.c_str());
  }
}

}  // namespace skyloc::cli
