// The one way skyloc parses TOML (the configuration and camera files): the text is checked
// for what toml++ 3.3.0 cannot parse safely before toml++ sees it, and parse errors come
// back as a Status naming the file, line and column. Users link skyloc::tomlpp (this header
// hands out toml++ tables).
#pragma once

#include <toml++/toml.h>

#include <string_view>

#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// Parses `text`; `source` names it in messages ("robot.toml:3:1: ..."). Refuses non-ASCII
// bytes outside strings and comments (see toml_text.cpp for why) with kInvalidArgument.
Result<toml::table> ParseTomlText(std::string_view text, const char* source);

}  // namespace skyloc::drivers
