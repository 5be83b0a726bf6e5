#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "skyloc/platform/crc32.h"
#include "support/scratch_dir.h"
#include "tools/chow_liu.h"
#include "tools/vocabulary.h"

namespace skyloc::tools {
namespace {

Vocabulary SmallVocabulary() {
  Vocabulary v;
  v.words = 4;
  for (int i = 0; i < v.words * kSiftDim; ++i)
    v.centres.push_back(static_cast<float>(i % 97) * 0.5f);
  v.samples = {{0, 2}, {1, 2, 3}, {}, {3}};
  const Result<ChowLiuTree> tree = LearnChowLiuTree(v.samples, v.words);
  EXPECT_TRUE(tree.ok());
  v.tree = *tree;
  return v;
}

std::vector<std::uint8_t> ReadAll(const std::string& path) {
  std::vector<std::uint8_t> b;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  EXPECT_NE(f, nullptr);
  if (f == nullptr)
    return b;
  int c = 0;
  while ((c = std::fgetc(f)) != EOF)
    b.push_back(static_cast<std::uint8_t>(c));
  std::fclose(f);
  return b;
}

void WriteAll(const std::string& path, const std::vector<std::uint8_t>& b) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  // An empty file is one of the cases: fwrite must not see empty()'s null data().
  if (!b.empty()) {
    ASSERT_EQ(std::fwrite(b.data(), 1, b.size(), f), b.size());
  }
  std::fclose(f);
}

// `good` with byte `at` XORed with `x` (or set to `x` when `set`).
std::vector<std::uint8_t> Patched(std::vector<std::uint8_t> b, std::size_t at, std::uint8_t x,
                                  bool set = false) {
  if (at < b.size())
    b[at] = set ? x : static_cast<std::uint8_t>(b[at] ^ x);
  return b;
}

bool Contains(const Status& s, const std::string& text) {
  return std::string(s.message()).find(text) != std::string::npos;
}

TEST(FabmapVocabulary, RoundTripsEveryField) {
  testing::ScratchDir dir("fabmap_vocab_");
  const std::string path = dir.path() + "/v.fabmap";
  Vocabulary v = SmallVocabulary();
  v.features.width = 320;
  v.features.max_features = 77;
  v.p_z_given_e = 0.5;
  v.p_z_given_not_e = 0.01;
  ASSERT_TRUE(SaveVocabulary(path, v).ok());
  const Result<Vocabulary> r = LoadVocabulary(path);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->features.width, 320);
  EXPECT_EQ(r->features.height, 270);
  EXPECT_EQ(r->features.max_features, 77);
  EXPECT_EQ(r->words, 4);
  EXPECT_EQ(r->centres, v.centres);
  EXPECT_EQ(r->tree.root, v.tree.root);
  EXPECT_EQ(r->tree.parent, v.tree.parent);
  EXPECT_EQ(r->tree.p_z, v.tree.p_z);
  EXPECT_EQ(r->tree.p_z_given_parent, v.tree.p_z_given_parent);
  EXPECT_EQ(r->tree.p_z_given_no_parent, v.tree.p_z_given_no_parent);
  EXPECT_EQ(r->p_z_given_e, 0.5);
  EXPECT_EQ(r->p_z_given_not_e, 0.01);
  EXPECT_EQ(r->samples, v.samples);
}

TEST(FabmapVocabulary, HeaderLayoutIsTheDocumentedOne) {
  // An independent reading of docs/FABMAP.md's layout: magic, version 1, the header CRC
  // over bytes 0..83 and the payload CRC over everything after the 88-byte header.
  testing::ScratchDir dir("fabmap_vocab_");
  const std::string path = dir.path() + "/v.fabmap";
  ASSERT_TRUE(SaveVocabulary(path, SmallVocabulary()).ok());
  const std::vector<std::uint8_t> b = ReadAll(path);
  ASSERT_GT(b.size(), 88u);
  EXPECT_EQ(std::memcmp(b.data(), "SKYLOCFM", 8), 0);
  std::uint32_t version = 0, header_crc = 0, payload_crc = 0, words = 0;
  std::memcpy(&version, b.data() + 8, 4);
  std::memcpy(&words, b.data() + 36, 4);
  std::memcpy(&payload_crc, b.data() + 80, 4);
  std::memcpy(&header_crc, b.data() + 84, 4);
  EXPECT_EQ(version, 1u);
  EXPECT_EQ(words, 4u);
  EXPECT_EQ(header_crc, Crc32({b.data(), 84}));
  EXPECT_EQ(payload_crc, Crc32({b.data() + 88, b.size() - 88}));
}

TEST(FabmapVocabulary, CorruptOrForeignFilesAreOneErrorNamingTheFile) {
  testing::ScratchDir dir("fabmap_vocab_");
  const std::string path = dir.path() + "/v.fabmap";
  ASSERT_TRUE(SaveVocabulary(path, SmallVocabulary()).ok());
  const std::vector<std::uint8_t> good = ReadAll(path);
  struct Case {
    const char* name;
    std::vector<std::uint8_t> bytes;
    const char* expect;
  };
  std::vector<Case> cases;
  ASSERT_GT(good.size(), 200u);
  cases.push_back({"payload bit", Patched(good, good.size() / 2, 0x40), "payload checksum"});
  // The word count in the header.
  cases.push_back({"header bit", Patched(good, 37, 0x01), "header checksum"});
  {
    auto b = good;
    b.resize(good.size() - 5);
    cases.push_back({"truncated", b, "size does not match"});
  }
  {
    auto b = good;
    b.resize(40);
    cases.push_back({"truncated header", b, "truncated header"});
  }
  cases.push_back(
      {"newer version", Patched(good, 8, 2, true), "version 2; this skyloc reads version 1"});
  cases.push_back({"no magic", Patched(good, 0, 'X', true), "not a skyloc FAB-MAP vocabulary"});
  cases.push_back({"empty", {}, "not a skyloc FAB-MAP vocabulary"});
  for (const Case& c : cases) {
    const std::string bad = dir.path() + "/bad.fabmap";
    WriteAll(bad, c.bytes);
    const Result<Vocabulary> r = LoadVocabulary(bad);
    ASSERT_FALSE(r.ok()) << c.name;
    EXPECT_TRUE(Contains(r.status(), bad)) << c.name << ": " << r.status().message();
    EXPECT_TRUE(Contains(r.status(), c.expect)) << c.name << ": " << r.status().message();
  }
  const Result<Vocabulary> missing = LoadVocabulary(dir.path() + "/none.fabmap");
  ASSERT_FALSE(missing.ok());
  EXPECT_TRUE(Contains(missing.status(), "none.fabmap"));
}

TEST(FabmapVocabulary, RefusesToWriteAnInconsistentVocabulary) {
  testing::ScratchDir dir("fabmap_vocab_");
  Vocabulary v = SmallVocabulary();
  v.tree.parent[static_cast<std::size_t>(v.tree.root == 0 ? 1 : 0)] = 9;  // not a word
  const Status s = SaveVocabulary(dir.path() + "/v.fabmap", v);
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(Contains(s, "v.fabmap")) << s.message();
}

}  // namespace
}  // namespace skyloc::tools
