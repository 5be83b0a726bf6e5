#include "skyloc/drivers/toml_keys.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <string_view>

namespace skyloc::drivers {
namespace {

long long Ll(std::int64_t v) {
  return static_cast<long long>(v);
}

std::string List(std::span<const char* const> names, bool quoted) {
  std::string s;
  for (const char* n : names) {
    if (!s.empty())
      s += ", ";
    s += quoted ? "\"" : "";
    s += n;
    s += quoted ? "\"" : "";
  }
  return s;
}

std::string Text(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

std::string Text(long long v) {
  char text[48];
  std::snprintf(text, sizeof text, "%lld", v);
  return text;
}

}  // namespace

TomlKeyReader::TomlKeyReader(const toml::table* table, const char* section, const char* source,
                             TomlKeyNaming naming)
    : table_(table), section_(section), source_(source), naming_(naming) {}

const toml::node* TomlKeyReader::Find(const char* key) {
  known_.emplace_back(key);
  if (table_ == nullptr || !error_.ok())
    return nullptr;
  return table_->get(key);
}

std::string TomlKeyReader::Default(const std::string& value) const {
  return naming_ == TomlKeyNaming::kSection ? " (default " + value + ")" : std::string();
}

bool TomlKeyReader::Has(const char* key) {
  known_.emplace_back(key);
  return table_ != nullptr && table_->get(key) != nullptr;
}

void TomlKeyReader::Fail(const toml::node* node, const char* key, const char* format, ...) {
  if (!error_.ok())
    return;
  char detail[256];
  va_list args;
  va_start(args, format);
  std::vsnprintf(detail, sizeof detail, format, args);
  va_end(args);
  char where[64] = "";
  if (node != nullptr && node->source().begin.line > 0)
    std::snprintf(where, sizeof where, ":%u", static_cast<unsigned>(node->source().begin.line));
  if (naming_ == TomlKeyNaming::kSection)
    error_ = Status::Error(StatusCode::kInvalidArgument, "%s%s: [%s] %s %s", source_, where,
                           section_, key, detail);
  else
    error_ = Status::Error(StatusCode::kInvalidArgument, "%s%s: %s.%s %s", source_, where, section_,
                           key, detail);
}

void TomlKeyReader::Int64(const char* key, std::int64_t* out, std::int64_t lo, std::int64_t hi) {
  const toml::node* node = Find(key);
  if (node == nullptr)
    return;
  char range[96];  // "1..100 (default 10)"
  std::snprintf(range, sizeof range, "%lld..%lld%s", Ll(lo), Ll(hi),
                Default(Text(Ll(*out))).c_str());
  const auto* value = node->as_integer();
  if (value == nullptr) {
    Fail(node, key, "must be an integer in %s", range);
    return;
  }
  const std::int64_t v = value->get();
  if (v < lo || v > hi) {
    Fail(node, key, "= %lld is out of range: must be %s", Ll(v), range);
    return;
  }
  *out = v;
}

void TomlKeyReader::Int(const char* key, int* out, std::int64_t lo, std::int64_t hi) {
  std::int64_t v = *out;
  Int64(key, &v, lo, hi);
  *out = static_cast<int>(v);
}

void TomlKeyReader::Double(const char* key, double* out, double lo, double hi) {
  const toml::node* node = Find(key);
  if (node == nullptr)
    return;
  const bool bounded = std::isfinite(lo) || std::isfinite(hi);
  char range[96] = "";  // "0.1..1000 (default 30)"
  if (bounded)
    std::snprintf(range, sizeof range, "%g..%g%s", lo, hi, Default(Text(*out)).c_str());
  double v = 0;
  if (const auto* f = node->as_floating_point()) {
    v = f->get();
  } else if (const auto* i = node->as_integer()) {
    v = static_cast<double>(i->get());
  } else {
    Fail(node, key, "must be a number%s%s", bounded ? " in " : "", range);
    return;
  }
  if (!std::isfinite(v) && !bounded) {
    Fail(node, key, "must be a finite number");
    return;
  }
  if (!std::isfinite(v) || v < lo || v > hi) {
    Fail(node, key, "= %g is out of range: must be %s", v, range);
    return;
  }
  *out = v;
}

void TomlKeyReader::Float(const char* key, float* out, double lo, double hi) {
  double v = static_cast<double>(*out);
  Double(key, &v, lo, hi);
  *out = static_cast<float>(v);
}

void TomlKeyReader::Numbers(const char* key, std::size_t count, double* out) {
  const toml::node* node = Find(key);
  if (node == nullptr)
    return;
  const toml::array* array = node->as_array();
  bool good = array != nullptr && array->size() == count;
  for (std::size_t i = 0; good && i < count; ++i) {
    const toml::node* item = array->get(i);
    good =
        item != nullptr && item->is_number() && std::isfinite(item->value<double>().value_or(NAN));
  }
  if (!good) {
    Fail(node, key, "must be an array of %zu numbers", count);
    return;
  }
  for (std::size_t i = 0; i < count; ++i)
    out[i] = array->get(i)->value<double>().value_or(NAN);
}

void TomlKeyReader::Bool(const char* key, bool* out) {
  const toml::node* node = Find(key);
  if (node == nullptr)
    return;
  const auto* value = node->as_boolean();
  if (value == nullptr) {
    Fail(node, key, "must be true or false%s", Default(*out ? "true" : "false").c_str());
    return;
  }
  *out = value->get();
}

void TomlKeyReader::String(const char* key, std::string* out, bool allow_empty) {
  const toml::node* node = Find(key);
  if (node == nullptr)
    return;
  const auto* value = node->as_string();
  if (value == nullptr) {
    Fail(node, key, "must be a string%s", Default("\"" + *out + "\"").c_str());
    return;
  }
  if (!allow_empty && value->get().empty()) {
    Fail(node, key, "must not be empty%s", Default("\"" + *out + "\"").c_str());
    return;
  }
  *out = value->get();
}

void TomlKeyReader::Path(const char* key, std::string* out) {
  const toml::node* node = Find(key);
  if (node == nullptr)
    return;
  std::string value = *out;
  String(key, &value, true);
  if (!error_.ok())
    return;
  const std::string_view source(source_);
  const std::size_t slash = source.rfind('/');
  if (!value.empty() && value[0] != '/' && slash != std::string_view::npos)
    value.insert(0, source.substr(0, slash + 1));
  *out = value;
}

void TomlKeyReader::Choice(const char* key, std::span<const char* const> names,
                           std::size_t* index) {
  const toml::node* node = Find(key);
  if (node == nullptr)
    return;
  if (const auto* value = node->as_string()) {
    std::size_t i = 0;
    for (const char* n : names) {
      if (value->get() == n) {
        *index = i;
        return;
      }
      ++i;
    }
  }
  const char* fallback = *index < names.size() ? names[*index] : "";
  if (naming_ == TomlKeyNaming::kSection)
    Fail(node, key, "must be one of %s (default \"%s\")", List(names, true).c_str(), fallback);
  else
    Fail(node, key, "must be one of %s", List(names, true).c_str());
}

void TomlKeyReader::OneOf(const char* key, std::string* out,
                          std::initializer_list<const char*> names) {
  std::size_t index = names.size();
  std::size_t i = 0;
  for (const char* n : names) {
    if (*out == n)
      index = i;
    ++i;
  }
  const std::span<const char* const> list(names.begin(), names.size());
  Choice(key, list, &index);
  if (index < list.size())
    *out = list[index];
}

void TomlKeyReader::Invalid(const char* key, const char* message) {
  known_.emplace_back(key);
  const toml::node* node = table_ == nullptr ? nullptr : table_->get(key);
  Fail(node != nullptr ? node : table_, key, "%s", message);
}

Status TomlKeyReader::Finish() {
  if (table_ == nullptr || !error_.ok())
    return error_;
  for (auto&& [k, node] : *table_) {
    bool known = false;
    for (const std::string& name : known_)
      known = known || k.str() == name;
    if (known)
      continue;
    std::string list;
    for (std::size_t i = 0; i < known_.size(); ++i) {
      bool repeated = false;  // a key may be read twice (Has, then read)
      for (std::size_t j = 0; j < i; ++j)
        repeated = repeated || known_[j] == known_[i];
      if (!repeated)
        list += (list.empty() ? "" : ", ") + known_[i];
    }
    const std::string key(k.str());
    const unsigned line = static_cast<unsigned>(node.source().begin.line);
    unknown_key_ = key;
    unknown_line_ = line;
    if (naming_ == TomlKeyNaming::kSection)
      error_ = Status::Error(StatusCode::kInvalidArgument,
                             "%s:%u: key %s is not known in [%s]: check its spelling and "
                             "section (known: %s)",
                             source_, line, key.c_str(), section_, list.c_str());
    else
      error_ = Status::Error(StatusCode::kInvalidArgument,
                             "%s:%u: unknown key '%s' in [%s]: remove it or use one of: %s",
                             source_, line, key.c_str(), section_, list.c_str());
    return error_;
  }
  return error_;
}

}  // namespace skyloc::drivers
