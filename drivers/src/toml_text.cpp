#include "skyloc/drivers/toml_text.h"

#include <cstdint>
#include <string>

namespace skyloc::drivers {
namespace {

// toml++ 3.3.0 (Debian 12) reaches __builtin_unreachable() for many non-ASCII characters
// where it looks for whitespace (is_non_ascii_horizontal_whitespace: U+00A1..U+0499 and
// others), which is undefined behaviour on a garbled or mistyped file; the config fuzz
// target found it. skyloc's keys and unquoted values are ASCII anyway, so non-ASCII text is
// accepted only inside strings and comments, where the parser does not make that check.
// A quote opens a string only where a value or a quoted key begins (a line's start,
// after '=', '[', '{' or ','): after a malformed value such as `3PPPPP"...` or
// `[38.59.'''...` the parser reads the bytes after the quote as code, and the camera-file
// fuzz target found it reaching the same unreachable point there. (So a quoted part of a
// dotted key, `a."b"`, must be ASCII: skyloc's keys are.)
// Returns the 1-based line and column of the first offending byte, or line 0.
struct TextPosition {
  int line = 0;
  int column = 0;
};
TextPosition FirstNonAsciiOutsideStrings(std::string_view text) {
  enum class Mode { kCode, kComment, kBasic, kLiteral, kMultiBasic, kMultiLiteral };
  Mode mode = Mode::kCode;
  int line = 1, column = 0;
  char last = '\n';  // the last character of code that was not whitespace
  const auto string_may_start = [&] {
    return last == '\n' || last == '=' || last == '[' || last == '{' || last == ',';
  };
  // A '#' opens a comment at a line's start or after whitespace: glued to a malformed
  // value (`3P#...`) toml++ may still be reading that value.
  const auto comment_may_start = [&](std::size_t i) {
    return i == 0 || text[i - 1] == ' ' || text[i - 1] == '\t' || text[i - 1] == '\n' ||
           text[i - 1] == '\r' || (last == '"' || last == '\'' || last == ']' || last == '}');
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    ++column;
    const auto starts = [&](const char* s) { return text.substr(i).starts_with(s); };
    switch (mode) {
      case Mode::kCode:
        if (static_cast<unsigned char>(c) >= 0x80)
          return {line, column};
        if (c == '#' && comment_may_start(i)) {
          mode = Mode::kComment;
        } else if ((c == '"' || c == '\'') && !string_may_start()) {
          last = c;  // a stray quote: what follows stays code
        } else if (starts("\"\"\"")) {
          mode = Mode::kMultiBasic;
          i += 2;
          column += 2;
        } else if (starts("'''")) {
          mode = Mode::kMultiLiteral;
          i += 2;
          column += 2;
        } else if (c == '"') {
          mode = Mode::kBasic;
        } else if (c == '\'') {
          mode = Mode::kLiteral;
        } else if (c == '\n') {
          last = '\n';
        } else if (c != ' ' && c != '\t' && c != '\r') {
          last = c;
        }
        break;
      case Mode::kComment:
        if (c == '\n') {
          mode = Mode::kCode;
          last = '\n';
        }
        break;
      case Mode::kBasic:
      case Mode::kMultiBasic:
        if (c == '\\') {
          // After a backslash toml++ looks for a line-ending backslash's whitespace with the
          // same check, so the character after it (and after any spaces) must be ASCII; no
          // escape is anything else. In a multi-line string it then trims the whitespace
          // and line breaks that follow, so the first character it keeps must be ASCII too.
          // (The camera-file fuzz target found `\<U+FEFD>` and `\<newline><U+FEDF>`.)
          std::size_t j = i + 1;
          while (j < text.size() && (text[j] == ' ' || text[j] == '\t' || text[j] == '\r'))
            ++j;
          if (j < text.size() && static_cast<unsigned char>(text[j]) >= 0x80)
            return {line, column + static_cast<int>(j - i)};
          if (mode == Mode::kMultiBasic) {
            if (j < text.size() && text[j] == '\n') {
              for (; i + 1 < j; ++i)
                ++column;
              for (; j < text.size() &&
                     (text[j] == ' ' || text[j] == '\t' || text[j] == '\r' || text[j] == '\n');
                   ++j) {
                if (text[j] == '\n') {
                  ++line;
                  column = 0;
                } else {
                  ++column;
                }
              }
              if (j < text.size() && static_cast<unsigned char>(text[j]) >= 0x80)
                return {line, column + 1};
              i = j - 1;  // the loop moves on to the first kept character
              continue;
            }
          }
          ++i;  // the escaped character cannot end the string
          ++column;
          if (i < text.size() && text[i] == '\n') {
            ++line;
            column = 0;
          }
          continue;
        }
        if (mode == Mode::kBasic && (c == '"' || c == '\n')) {
          mode = Mode::kCode;
          last = c;
        } else if (mode == Mode::kMultiBasic && starts("\"\"\"")) {
          mode = Mode::kCode;
          last = '"';
          i += 2;
          column += 2;
        }
        break;
      case Mode::kLiteral:
        if (c == '\'' || c == '\n') {
          mode = Mode::kCode;
          last = c;
        }
        break;
      case Mode::kMultiLiteral:
        if (starts("'''")) {
          mode = Mode::kCode;
          last = '\'';
          i += 2;
          column += 2;
        }
        break;
    }
    if (c == '\n') {
      ++line;
      column = 0;
    }
  }
  return {};
}

// The code points on which toml++ 3.3.0's is_non_ascii_horizontal_whitespace() falls
// through to TOML_UNREACHABLE (computed from its generated tables): wherever the parser
// asks "is this whitespace?" of one of them, behaviour is undefined. The scanner above
// keeps non-ASCII text out of the places it knows the parser asks, but four fuzzer finds
// in a row were places it did not know (text after a malformed value or an escape), so
// these code points are refused everywhere, in strings and comments too. Other non-ASCII
// text (U+2014 dashes, U+2192 arrows, CJK, ...) stays allowed in strings and comments.
bool ParserMisreads(std::uint32_t c) {
  return (c >= 0xA1 && c <= 0x499) || (c >= 0x2C5E && c <= 0x2FFF) ||
         (c >= 0x3001 && c <= 0x3057) || (c >= 0xFB26 && c <= 0xFEFE);
}

struct MisreadCharacter {
  int line = 0;  // 0: none
  int column = 0;
  std::uint32_t code_point = 0;
};

// Columns count code points, as toml++'s own error positions do.
MisreadCharacter FirstMisreadCharacter(std::string_view text) {
  int line = 1, column = 0;
  for (std::size_t i = 0; i < text.size();) {
    const auto b = static_cast<unsigned char>(text[i]);
    ++column;
    if (b == '\n') {
      ++line;
      column = 0;
      ++i;
      continue;
    }
    std::size_t length = 1;
    std::uint32_t c = b;
    if (b >= 0xC0 && b < 0xE0) {
      length = 2;
      c = b & 0x1Fu;
    } else if (b >= 0xE0 && b < 0xF0) {
      length = 3;
      c = b & 0x0Fu;
    } else if (b >= 0xF0 && b < 0xF8) {
      length = 4;
      c = b & 0x07u;
    }
    if (length > 1 && i + length <= text.size()) {
      for (std::size_t k = 1; k < length; ++k)
        c = (c << 6) | (static_cast<unsigned char>(text[i + k]) & 0x3Fu);
      if (ParserMisreads(c))
        return {line, column, c};
    }
    i += length > 1 && i + length <= text.size() ? length : 1;
  }
  return {};
}

}  // namespace

Result<toml::table> ParseTomlText(std::string_view text, const char* source) {
  if (const MisreadCharacter m = FirstMisreadCharacter(text); m.line > 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "%s:%d:%d: the character U+%04X cannot be read: the TOML library "
                         "skyloc uses (toml++ 3.3.0) has undefined behaviour on it; in a string "
                         "write it as \\u%04X, in a comment leave it out",
                         source, m.line, m.column, static_cast<unsigned>(m.code_point),
                         static_cast<unsigned>(m.code_point));
  }
  if (const TextPosition p = FirstNonAsciiOutsideStrings(text); p.line > 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "%s:%d:%d: a non-ASCII character outside a string or comment: keys "
                         "and unquoted values are ASCII",
                         source, p.line, p.column);
  }
  toml::parse_result parsed = toml::parse(text, std::string_view(source));
  if (!parsed) {
    const toml::parse_error& e = parsed.error();
    const std::string description(e.description());
    return Status::Error(StatusCode::kInvalidArgument, "%s:%u:%u: not valid TOML: %s", source,
                         static_cast<unsigned>(e.source().begin.line),
                         static_cast<unsigned>(e.source().begin.column), description.c_str());
  }
  return std::move(parsed).table();
}

}  // namespace skyloc::drivers
