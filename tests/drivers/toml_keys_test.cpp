// The typed TOML key reader: values in range are stored, a wrong type or range names the
// file, line, section and key, and a key nobody asked for is refused naming the section and
// listing the known keys, however many keys the section has.
#include "skyloc/drivers/toml_keys.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "skyloc/drivers/toml_text.h"

namespace skyloc::drivers {
namespace {

using ::testing::HasSubstr;

toml::table Parse(const std::string& text) {
  Result<toml::table> t = ParseTomlText(text, "robot.toml");
  EXPECT_TRUE(t.ok()) << t.status().message();
  // Moved, not copied: a copied toml++ node forgets where it was in the file.
  return t.ok() ? std::move(*t) : toml::table{};
}

// A section of `n` keys k0..k{n-1}, key i holding the value i * 10.
std::string ManyKeys(int n) {
  std::string text = "[big]\n";
  for (int i = 0; i < n; ++i)
    text += "k" + std::to_string(i) + " = " + std::to_string(i * 10) + "\n";
  return text;
}

TEST(TomlKeyReader, ReadsEveryTypeInRange) {
  const toml::table root = Parse(
      "[s]\nn = 7\nx = 2.5\ny = 3\nflag = true\nname = \"dawn\"\npair = [1, -2.5]\n"
      "pick = \"time\"\n");
  TomlKeyReader r(root.get_as<toml::table>("s"), "s", "robot.toml", TomlKeyNaming::kSection);
  int n = 0;
  double x = 0, y = 0, pair[2] = {};
  bool flag = false;
  std::string name, pick = "distance";
  r.Int("n", &n, 0, 10);
  r.Double("x", &x, 0, 10);
  r.Double("y", &y, 0, 10);  // an integer is a number
  r.Bool("flag", &flag);
  r.String("name", &name, false);
  r.Numbers("pair", 2, pair);
  r.OneOf("pick", &pick, {"distance", "time"});
  ASSERT_TRUE(r.Finish().ok()) << r.status().message();
  EXPECT_EQ(n, 7);
  EXPECT_EQ(x, 2.5);
  EXPECT_EQ(y, 3.0);
  EXPECT_TRUE(flag);
  EXPECT_EQ(name, "dawn");
  EXPECT_EQ(pair[0], 1.0);
  EXPECT_EQ(pair[1], -2.5);
  EXPECT_EQ(pick, "time");
}

TEST(TomlKeyReader, AbsentKeysKeepTheirDefaults) {
  const toml::table root = Parse("[s]\n");
  TomlKeyReader r(root.get_as<toml::table>("s"), "s", "robot.toml", TomlKeyNaming::kSection);
  int n = 4;
  r.Int("n", &n, 0, 10);
  EXPECT_FALSE(r.Has("n"));
  EXPECT_TRUE(r.Finish().ok());
  EXPECT_EQ(n, 4);
}

TEST(TomlKeyReader, WrongValuesNameFileLineSectionAndKey) {
  const toml::table root = Parse("[s]\nok = 1\nn = 11\n");
  TomlKeyReader r(root.get_as<toml::table>("s"), "s", "robot.toml", TomlKeyNaming::kSection);
  int ok = 0, n = 5;
  r.Int("ok", &ok, 0, 10);
  r.Int("n", &n, 0, 10);
  EXPECT_EQ(std::string(r.Finish().message()),
            "robot.toml:3: [s] n = 11 is out of range: must be 0..10 (default 5)");
  EXPECT_EQ(n, 5);

  TomlKeyReader dotted(root.get_as<toml::table>("s"), "lens", "cam.toml", TomlKeyNaming::kDotted);
  double d = 0;
  dotted.Double("n", &d, 0, 10);
  EXPECT_EQ(std::string(dotted.status().message()),
            "cam.toml:3: lens.n = 11 is out of range: must be 0..10");
}

TEST(TomlKeyReader, TheFirstErrorWins) {
  const toml::table root = Parse("[s]\na = \"x\"\nb = -1\n");
  TomlKeyReader r(root.get_as<toml::table>("s"), "s", "robot.toml", TomlKeyNaming::kSection);
  int a = 0, b = 0;
  r.Int("a", &a, 0, 10);
  r.Int("b", &b, 0, 10);
  EXPECT_THAT(r.Finish().message(), HasSubstr("robot.toml:2: [s] a must be an integer"));
}

// More keys than the reader of old could remember (32): each is read, none is mistaken
// for unknown, and an unknown one after them is still refused.
TEST(TomlKeyReader, ASectionOfFortyKeys) {
  constexpr int kKeys = 40;
  const toml::table root = Parse(ManyKeys(kKeys) + "k_unknown = 1\n");
  TomlKeyReader r(root.get_as<toml::table>("big"), "big", "robot.toml", TomlKeyNaming::kSection);
  std::vector<int> values(kKeys, -1);
  for (int i = 0; i < kKeys; ++i) {
    const std::string key = "k" + std::to_string(i);
    r.Int(key.c_str(), &values[static_cast<std::size_t>(i)], 0, 1000);
  }
  const Status s = r.Finish();
  for (int i = 0; i < kKeys; ++i)
    EXPECT_EQ(values[static_cast<std::size_t>(i)], i * 10) << "k" << i;
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(s.message(), HasSubstr("robot.toml:42: key k_unknown is not known in [big]"));
  EXPECT_THAT(s.message(), HasSubstr("(known: k0, k1, k2,"));

  // The same forty keys without the stranger: nothing refused.
  const toml::table clean = Parse(ManyKeys(kKeys));
  TomlKeyReader all(clean.get_as<toml::table>("big"), "big", "robot.toml", TomlKeyNaming::kSection);
  for (int i = 0; i < kKeys; ++i) {
    int v = 0;
    all.Int(("k" + std::to_string(i)).c_str(), &v, 0, 1000);
  }
  EXPECT_TRUE(all.Finish().ok()) << all.status().message();
}

TEST(TomlKeyReader, UnknownKeyListsTheKnownOnes) {
  const toml::table root = Parse("[lens]\nfov_dg = 185\n");
  TomlKeyReader r(root.get_as<toml::table>("lens"), "lens", "cam.toml", TomlKeyNaming::kDotted);
  EXPECT_FALSE(r.Has("fov_deg"));
  EXPECT_FALSE(r.Has("model"));
  EXPECT_EQ(std::string(r.Finish().message()),
            "cam.toml:2: unknown key 'fov_dg' in [lens]: remove it or use one of: fov_deg, model");
}

TEST(TomlKeyReader, InvalidPointsAtTheKeyOrTheSection) {
  const toml::table root = Parse("\n[s]\nlo = 5\n");
  TomlKeyReader r(root.get_as<toml::table>("s"), "s", "robot.toml", TomlKeyNaming::kSection);
  r.Invalid("hi", "must be given with lo");
  EXPECT_EQ(std::string(r.status().message()), "robot.toml:2: [s] hi must be given with lo");
  TomlKeyReader at_key(root.get_as<toml::table>("s"), "s", "robot.toml", TomlKeyNaming::kSection);
  at_key.Invalid("lo", "must not exceed hi");
  EXPECT_EQ(std::string(at_key.status().message()), "robot.toml:3: [s] lo must not exceed hi");
}

}  // namespace
}  // namespace skyloc::drivers
