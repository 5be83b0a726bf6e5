// The option table every command parses its arguments with: values in range are stored,
// anything else is refused with exit 2 and one message naming the option, its value and
// what a good value looks like.
#include "cli/options.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "support/command_line.h"

namespace skyloc::cli {
namespace {

// Arguments as main() hands them over (mutable C strings).
using Args = skyloc::testing::CommandLine;

enum class Colour : std::uint8_t { kRed, kBlue };

struct Parsed {
  bool force = false;
  std::string route;
  int ds = 10;
  std::uint64_t frames = 0;
  double tilt = 0;
  std::vector<int> ds_list;
  Colour colour = Colour::kRed;
  std::vector<std::string> files;
  OptionTable table{"test", "[options] FILE...", "A table for the tests.\n"};
  Parsed() {
    table.Flag("--force", "replace it", &force);
    table.Text("--route", "FILE", "the route", &route);
    table.Int("--ds", "N", "sequence length in frames", 1, 1000, &ds);
    table.Count("--frames", "N", "stop after N frames", &frames);
    table.Number("--tilt", "DEG", "constant pitch", {-90, 90}, &tilt);
    table.IntList("--len", "N", "lengths to compare", 1, 50, &ds_list);
    table.Choice("--colour", "the colour", {{"red", Colour::kRed}, {"blue", Colour::kBlue}},
                 &colour);
    table.Positional("FILE", "images", 1, 3, &files);
  }
};

TEST(OptionTable, StoresEveryKindOfValue) {
  Parsed p;
  const Args a({"--force", "--route", "r.db", "--ds", "20", "--frames", "123", "--tilt", "-12.5",
                "--len", "3", "--len", "7", "--colour", "blue", "a.png", "b.png"});
  ASSERT_EQ(p.table.Parse(a.span()), ParseOutcome::kRun);
  EXPECT_TRUE(p.force);
  EXPECT_EQ(p.route, "r.db");
  EXPECT_EQ(p.ds, 20);
  EXPECT_EQ(p.frames, 123u);
  EXPECT_DOUBLE_EQ(p.tilt, -12.5);
  EXPECT_EQ(p.ds_list, (std::vector<int>{3, 7}));
  EXPECT_EQ(p.colour, Colour::kBlue);
  EXPECT_EQ(p.files, (std::vector<std::string>{"a.png", "b.png"}));
  EXPECT_TRUE(p.table.Given("--ds"));
  EXPECT_FALSE(Parsed().table.Given("--ds"));
}

// Each refusal: exit 2, the option and its value named, and what would be accepted.
TEST(OptionTable, RefusesBadValuesNamingTheOptionAndTheRange) {
  struct Case {
    std::vector<std::string> args;
    std::string expected;
  };
  const Case cases[] = {
      {{"--ds", "0", "a"}, "--ds '0': expected a whole number in 1..1000 (sequence length"},
      {{"--ds", "2.5", "a"}, "--ds '2.5': expected a whole number in 1..1000"},
      {{"--frames", "-1", "a"}, "--frames '-1': expected a whole number >= 0"},
      {{"--tilt", "91", "a"}, "--tilt '91': expected a number in [-90, 90]"},
      {{"--tilt", "nan", "a"}, "--tilt 'nan': expected a number in [-90, 90]"},
      {{"--colour", "green", "a"}, "--colour 'green': expected red or blue"},
      {{"--route"}, "--route needs a value: FILE"},
      {{"--route", "", "a"}, "--route '': expected a value that is not empty"},
      {{"--bogus", "a"}, "unknown option '--bogus'"},
      {{"--ds", "2", "--ds", "3", "a"}, "--ds is given twice"},
      {{}, "missing FILE (images)"},
      {{"a", "b", "c", "d"}, "unexpected argument 'd' (at most 3 FILE)"},
  };
  for (const Case& c : cases) {
    Parsed p;
    const Args a(c.args);
    ::testing::internal::CaptureStderr();
    const ParseOutcome outcome = p.table.Parse(a.span());
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(outcome, ParseOutcome::kRefused) << c.expected;
    EXPECT_EQ(ExitCode(outcome), kExitUsage);
    EXPECT_NE(err.find("skyloc test: " + c.expected), std::string::npos) << err;
    EXPECT_NE(err.find("Run 'skyloc test --help'"), std::string::npos) << err;
  }
}

TEST(OptionTable, HelpListsEveryOptionWithItsValueAndLine) {
  Parsed p;
  const Args a({"--ds", "0", "--help"});  // --help wins over a bad value
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(p.table.Parse(a.span()), ParseOutcome::kHelpPrinted);
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(ExitCode(ParseOutcome::kHelpPrinted), kExitOk);
  EXPECT_EQ(out.rfind("usage: skyloc test [options] FILE...\n", 0), 0u) << out;
  for (const char* line : {"--force", "--route FILE", "--ds N", "sequence length in frames",
                           "--colour red|blue", "A table for the tests."})
    EXPECT_NE(out.find(line), std::string::npos) << line << "\n" << out;
}

// A list of choices: every occurrence appends its value, in order; a wrong name is refused.
TEST(OptionTable, ChoiceListAppendsEachOccurrence) {
  std::vector<Colour> colours;
  OptionTable table{"test", "[options]", ""};
  table.ChoiceList("--colour", "colours to compare",
                   {{"red", Colour::kRed}, {"blue", Colour::kBlue}}, &colours);
  const Args a({"--colour", "blue", "--colour", "red", "--colour", "blue"});
  ASSERT_EQ(table.Parse(a.span()), ParseOutcome::kRun);
  EXPECT_EQ(colours, (std::vector<Colour>{Colour::kBlue, Colour::kRed, Colour::kBlue}));
  std::vector<Colour> refused;
  OptionTable other{"test", "[options]", ""};
  other.ChoiceList("--colour", "colours", {{"red", Colour::kRed}}, &refused);
  const Args bad({"--colour", "green"});
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(other.Parse(bad.span()), ParseOutcome::kRefused);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("--colour 'green': expected red"),
            std::string::npos);
  EXPECT_TRUE(refused.empty());
}

// An option bound to a std::optional: empty unless given, the value when given, and a
// refused value leaves it empty (a setting that replaces the configuration's only when given).
TEST(OptionTable, OptionalDestinationsHoldAValueOnlyWhenGiven) {
  struct Optionals {
    std::optional<int> ds;
    std::optional<double> tilt;
    std::optional<Colour> colour;
    OptionTable table{"test", "[options]", ""};
    Optionals() {
      table.Int("--ds", "N", "sequence length", 1, 1000, &ds);
      table.Number("--tilt", "DEG", "pitch", {-90, 90}, &tilt);
      table.Choice("--colour", "the colour", {{"red", Colour::kRed}, {"blue", Colour::kBlue}},
                   &colour);
    }
  };
  Optionals none;
  ASSERT_EQ(none.table.Parse(Args({}).span()), ParseOutcome::kRun);
  EXPECT_FALSE(none.ds.has_value());
  EXPECT_FALSE(none.tilt.has_value());
  EXPECT_FALSE(none.colour.has_value());
  Optionals all;
  const Args a({"--ds", "20", "--tilt", "-12.5", "--colour", "red"});
  ASSERT_EQ(all.table.Parse(a.span()), ParseOutcome::kRun);
  EXPECT_EQ(all.ds, 20);
  EXPECT_EQ(all.tilt, -12.5);
  EXPECT_EQ(all.colour, Colour::kRed);
  Optionals refused;
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(refused.table.Parse(Args({"--tilt", "91"}).span()), ParseOutcome::kRefused);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("--tilt '91': expected a number in"),
            std::string::npos);
  EXPECT_FALSE(refused.tilt.has_value());
}

}  // namespace
}  // namespace skyloc::cli
