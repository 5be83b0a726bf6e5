// The one typed TOML key reader (the configuration's sections, the camera file's tables):
// each read checks the type and range of one key and names its file:line when it is
// wrong; every key asked for is remembered (no limit on how many), so Finish() refuses a
// key nobody asked for, naming the section and listing the known keys. The first error
// wins; reads after it change nothing. Tables come from ParseTomlText (toml_text.h).
#pragma once

#include <toml++/toml.h>

#include <cstdint>
#include <initializer_list>
#include <span>
#include <string>
#include <vector>

#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// How a key is named in messages, after the file's documentation: the configuration's
// "[camera] kind" (every key has a default, which a message gives) or the camera file's
// "lens.fov_deg" (its keys describe one camera: no default to give).
enum class TomlKeyNaming : std::uint8_t { kSection, kDotted };

class TomlKeyReader {
 public:
  // `table` may be null (the section is absent: every read leaves its default). `section`
  // and `source` (the file's name) must outlive the reader.
  TomlKeyReader(const toml::table* table, const char* section, const char* source,
                TomlKeyNaming naming);

  // Whole numbers in lo..hi.
  void Int64(const char* key, std::int64_t* out, std::int64_t lo, std::int64_t hi);
  void Int(const char* key, int* out, std::int64_t lo, std::int64_t hi);
  // A finite number (an integer is taken as one) in lo..hi; infinite bounds: any.
  void Double(const char* key, double* out, double lo, double hi);
  // A float parameter: read as a double, range checked, rounded to float once.
  void Float(const char* key, float* out, double lo, double hi);
  // An array of exactly `count` finite numbers.
  void Numbers(const char* key, std::size_t count, double* out);
  void Bool(const char* key, bool* out);
  void String(const char* key, std::string* out, bool allow_empty);
  // A file or folder (empty: unset). A relative path is relative to the folder of the file
  // being read (`source`), not the working directory (systemd starts skyloc in /): the
  // one rule for every path key.
  void Path(const char* key, std::string* out);
  // One of `names`; `*index` is the chosen one's position (its value on entry names the
  // default in the message).
  void Choice(const char* key, std::span<const char* const> names, std::size_t* index);
  void OneOf(const char* key, std::string* out, std::initializer_list<const char*> names);

  // Declares keys as known without reading them (read by hand, or refused for a reason
  // of their own); returns whether `key` is present.
  bool Has(const char* key);
  // An error about `key` (a combination of keys): at its line, or the section's when it
  // is absent.
  void Invalid(const char* key, const char* message);
  // Refuses the first key nobody asked for; returns the first error of all.
  Status Finish();
  const Status& status() const { return error_; }
  // The keys asked for so far (each once or more).
  const std::vector<std::string>& known_keys() const { return known_; }
  // The key Finish() refused and its line; empty when it refused none.
  const std::string& unknown_key() const { return unknown_key_; }
  unsigned unknown_line() const { return unknown_line_; }
  bool ok() const { return error_.ok(); }

 private:
  const toml::node* Find(const char* key);
  std::string Default(const std::string& value) const;  // " (default VALUE)" or nothing
  void Fail(const toml::node* node, const char* key, const char* format, ...)
      __attribute__((format(printf, 4, 5)));

  const toml::table* table_;
  const char* section_;
  const char* source_;
  TomlKeyNaming naming_;
  std::vector<std::string> known_;
  std::string unknown_key_;
  unsigned unknown_line_ = 0;
  Status error_;
};

}  // namespace skyloc::drivers
