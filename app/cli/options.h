// The one command-line option parser of every skyloc command. A command lists its options
// in a table (name, value name, help line, range or choices, where the value goes); the
// table parses the arguments, refuses a bad one with one message in one style, and prints
// the help. Exit codes: kExitUsage (2) for a bad command line, kExitFailure (1) for a
// failure after it parsed (commands.h).
//
// Every command is a parser, which fills the command's options from the table and returns
// the ParseOutcome, and a body, which runs on the options; RunParsed (below) joins them:
//
//   ParseOutcome ParseArgs(std::span<char* const> args, Options* o) {
//     OptionTable t("teach", "--route FILE.db [options]", "Records a route ...");
//     t.Text("--route", "FILE.db", "the route database to write", &o->route);
//     t.Count("--frames", "N", "stop after N frames (default: until a signal)", &o->frames);
//     t.Number("--tilt", "DEG", "constant pitch of the simulated run", {-90, 90}, &o->tilt);
//     if (const ParseOutcome p = t.Parse(args); p != ParseOutcome::kRun) return p;
//     if (o->route.empty()) return t.Refuse("--route FILE.db is required");
//     return ParseOutcome::kRun;
//   }
//   int RunTeach(std::span<char* const> args) { return RunParsed(args, ParseArgs, Teach); }
//
// A bad value is told as "skyloc teach: --frames 'x': expected a whole number >= 0 (stop
// after N frames ...)" followed by where the options are described.
#pragma once

#include <cstdint>
#include <cstdio>
#include <functional>
#include <initializer_list>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace skyloc::cli {

// What Parse found: run the command, the help was printed (exit 0), or the command line
// was refused and the reason printed (exit 2).
enum class ParseOutcome : std::uint8_t { kRun, kHelpPrinted, kRefused };
int ExitCode(ParseOutcome outcome);  // kRun: 0 as well; the caller runs instead

// How every command starts: `parse` fills a default Options from the command line (its
// table, then the checks across options); after --help the command ends with 0, after a
// refused command line with 2, else `run` does the command on the options and returns its
// exit code.
template <typename Options, typename Run>
int RunParsed(std::span<char* const> args,
              ParseOutcome (*parse)(std::span<char* const> args, Options* options), Run run) {
  Options options;
  if (const ParseOutcome outcome = parse(args, &options); outcome != ParseOutcome::kRun)
    return ExitCode(outcome);
  return run(options);
}

// A closed or open interval of real numbers for Number().
struct NumberRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;  // true: the value must be > min, not >= min
  bool max_open = false;
};
// (0, inf): a length, a rate, a tolerance.
inline constexpr NumberRange kPositive{0, std::numeric_limits<double>::infinity(), true, false};

// The value type of an option's destination: E itself, or E inside a std::optional.
template <typename Out>
struct ChoiceOf {
  using type = Out;
};
template <typename E>
struct ChoiceOf<std::optional<E>> {
  using type = E;
};

class OptionTable {
 public:
  // `synopsis` follows "usage: skyloc COMMAND "; `description` is the prose under it.
  OptionTable(const char* command, const char* synopsis, const char* description);

  // A flag without a value.
  void Flag(const char* name, const char* help, bool* out);
  // Any text (a path, a name checked later).
  void Text(const char* name, const char* value, const char* help, std::string* out);
  // Repeatable text: each occurrence appends one.
  void TextList(const char* name, const char* value, const char* help,
                std::vector<std::string>* out);
  // A whole number in [min, max]. Here and below, an option bound to a std::optional holds
  // a value only when it was given (a setting that replaces another only then).
  void Int(const char* name, const char* value, const char* help, std::int64_t min,
           std::int64_t max, int* out);
  void Int(const char* name, const char* value, const char* help, std::int64_t min,
           std::int64_t max, std::optional<int>* out);
  void Int(const char* name, const char* value, const char* help, std::int64_t min,
           std::int64_t max, std::int64_t* out);
  // A whole number >= 0 (a count, a seed).
  void Count(const char* name, const char* value, const char* help, std::uint64_t* out);
  // Repeatable whole numbers in [min, max]: each occurrence appends one.
  void IntList(const char* name, const char* value, const char* help, std::int64_t min,
               std::int64_t max, std::vector<int>* out);
  // A finite real number in `range`.
  void Number(const char* name, const char* value, const char* help, NumberRange range,
              double* out);
  void Number(const char* name, const char* value, const char* help, NumberRange range,
              std::optional<double>* out);
  // Two finite numbers "A,B" (a range, a direction) that `accept` takes; `expected`
  // tells what a good value looks like when it does not.
  void NumberPair(const char* name, const char* value, const char* help, const char* expected,
                  std::function<bool(double a, double b)> accept, double* a, double* b);
  // One of the named values; `repeat` appends each occurrence to `list` instead.
  // The values are copied: an initializer_list's array lives only as long as the call.
  template <typename Out, typename E = typename ChoiceOf<Out>::type>
  void Choice(const char* name, const char* help,
              std::initializer_list<std::pair<const char*, std::type_identity_t<E>>> choices,
              Out* out) {
    AddChoice(name, help, Names(choices), false,
              [out, values = Values(choices)](std::size_t i) { *out = values[i]; });
  }
  template <typename E>
  void ChoiceList(const char* name, const char* help,
                  std::initializer_list<std::pair<const char*, E>> choices, std::vector<E>* list) {
    AddChoice(name, help, Names(choices), true,
              [list, values = Values(choices)](std::size_t i) { list->push_back(values[i]); });
  }
  // A value the command parses itself (e.g. "X,Y"): `parse` returns false and sets
  // `expected` (what a good value looks like) to refuse it.
  void Custom(const char* name, const char* value, const char* help,
              std::function<bool(const char* text, std::string* expected)> parse);
  // Words that are not options, in order: between `min` and `max` of them.
  void Positional(const char* value, const char* help, std::size_t min, std::size_t max,
                  std::vector<std::string>* out);

  // Parses `args` (the words after the command's name). --help / -h anywhere prints the
  // help on stdout. Every option may be given once unless it is a list.
  ParseOutcome Parse(std::span<char* const> args);
  // True when the option was on the command line (after Parse).
  bool Given(std::string_view name) const;
  // A refusal found after Parse (options that exclude each other, a missing one): prints
  // "skyloc COMMAND: WHAT" and where the options are described; returns kRefused.
  ParseOutcome Refuse(std::string_view what) const;
  void PrintHelp(std::FILE* out) const;
  const char* command() const { return command_; }

 private:
  struct Option {
    std::string name;
    std::string value;  // empty: a flag
    std::string help;
    bool repeatable = false;
    bool given = false;
    // Parses and stores; false with `expected` set refuses the value.
    std::function<bool(const char* text, std::string* expected)> store;
  };
  template <typename E>
  static std::vector<std::string> Names(std::initializer_list<std::pair<const char*, E>> choices) {
    std::vector<std::string> names;
    for (const auto& c : choices)
      names.emplace_back(c.first);
    return names;
  }
  template <typename E>
  static std::vector<E> Values(std::initializer_list<std::pair<const char*, E>> choices) {
    std::vector<E> values;
    for (const auto& c : choices)
      values.push_back(c.second);
    return values;
  }
  void AddChoice(const char* name, const char* help, std::vector<std::string> names,
                 bool repeatable, std::function<void(std::size_t)> pick);
  void AddNumber(const char* name, const char* value, const char* help, NumberRange range,
                 std::function<void(double)> store);
  void Add(Option option);
  Option* Find(std::string_view name);
  const Option* Find(std::string_view name) const;

  const char* command_;
  const char* synopsis_;
  const char* description_;
  std::vector<Option> options_;
  struct PositionalSpec {
    std::string value, help;
    std::size_t min = 0, max = 0;
    std::vector<std::string>* out = nullptr;
  };
  std::optional<PositionalSpec> positional_;  // a command takes one kind of word at most
};

}  // namespace skyloc::cli
