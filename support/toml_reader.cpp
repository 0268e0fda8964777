#include "support/toml_reader.hpp"

#include "support/input_error.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <set>
#include <fstream>
#include <sstream>

namespace drom {

std::string Range::describe() const {
  std::ostringstream s;
  const bool has_min = min > -1e299, has_max = max < 1e299;
  if (has_min && has_max) s << "in " << (min_exclusive ? "(" : "[") << min << ", " << max << (max_exclusive ? ")" : "]");
  else if (has_min) s << (min_exclusive ? "> " : ">= ") << min;
  else if (has_max) s << (max_exclusive ? "< " : "<= ") << max;
  else s << "finite";
  return s.str();
}

bool Range::contains(double v) const {
  if (!std::isfinite(v)) return false;
  if (min_exclusive ? v <= min : v < min) return false;
  if (max_exclusive ? v >= max : v > max) return false;
  return true;
}

struct TomlReader::Impl {
  toml::table root;
  std::set<std::string> consumed;
  std::set<std::string> overridden;

  static std::vector<std::string> split(const std::string& key) {
    std::vector<std::string> parts;
    std::stringstream ss(key);
    std::string part;
    while (std::getline(ss, part, '.')) parts.push_back(part);
    return parts;
  }
  // An array index: digits, few enough for stoul (an array of a billion entries is no case file).
  static bool is_index(const std::string& s) { return !s.empty() && s.size() <= 9 && s.find_first_not_of("0123456789") == std::string::npos; }

  toml::node* find(const std::string& key) {
    toml::node* node = &root;
    for (const auto& part : split(key)) {
      if (auto* t = node->as_table()) {
        node = t->get(part);
      } else if (auto* a = node->as_array(); a && is_index(part)) {
        node = a->get(std::stoul(part));
      } else {
        return nullptr;
      }
      if (!node) return nullptr;
    }
    return node;
  }
};

TomlReader::TomlReader(const std::string& text, std::string origin) : impl_(std::make_unique<Impl>()), origin_(std::move(origin)) {
  try {
    impl_->root = toml::parse(text, origin_);
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << origin_ << ":" << e.source().begin.line << ": not valid TOML: " << e.description();
    throw InputError(msg.str());
  }
}

TomlReader::TomlReader(const std::string& text, std::string origin, const std::vector<std::string>& overrides) : TomlReader(text, std::move(origin)) {
  for (const auto& o : overrides) apply_override(o);
}

TomlReader::~TomlReader() = default;

std::string read_input_file(const std::filesystem::path& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open the " + what + " (missing or unreadable)");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void TomlReader::apply_override(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) throw InputError("--set '" + printable(assignment) + "': expected key=value");
  const std::string key = assignment.substr(0, eq), value = assignment.substr(eq + 1);
  toml::table parsed;
  try {
    parsed = toml::parse("v = " + value);
  } catch (const toml::parse_error&) {
    parsed.insert("v", value);  // a bare word: take it as a string
  }
  const auto parts = Impl::split(key);
  toml::node* node = &impl_->root;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    if (auto* t = node->as_table()) {
      if (!t->get(parts[i])) t->insert(parts[i], toml::table{});
      node = t->get(parts[i]);
    } else if (auto* a = node->as_array(); a && Impl::is_index(parts[i]) && std::stoul(parts[i]) < a->size()) {
      node = a->get(std::stoul(parts[i]));
    } else {
      throw InputError("--set " + printable(key) + ": '" + printable(parts[i]) + "' is not a table in the case");
    }
  }
  if (auto* t = node->as_table()) {
    t->insert_or_assign(parts.back(), *parsed.get("v"));
  } else if (auto* a = node->as_array(); a && Impl::is_index(parts.back()) && std::stoul(parts.back()) < a->size()) {
    a->replace(a->begin() + static_cast<std::ptrdiff_t>(std::stoul(parts.back())), *parsed.get("v"));
  } else {
    throw InputError("--set " + printable(key) + ": cannot assign inside a value");
  }
  impl_->overridden.insert(key);
}

std::string TomlReader::where(const std::string& key) const {
  std::ostringstream msg;
  if (impl_->overridden.count(key)) {
    msg << "--set " << printable(key);
  } else if (auto* node = impl_->find(key); node && node->source().begin.line > 0) {
    msg << origin_ << ":" << node->source().begin.line << ": " << printable(key);
  } else {
    msg << origin_ << ": " << printable(key);
  }
  return msg.str();
}

void TomlReader::fail(const std::string& key, const std::string& message) const {
  // "key = value: expected ..." reads better than "key: = value: expected ..."
  const std::string sep = message.rfind("= ", 0) == 0 ? " " : ": ";
  throw InputError(where(key) + sep + message);
}

bool TomlReader::has(const std::string& key) const { return impl_->find(key) != nullptr; }

bool TomlReader::is_text(const std::string& key) const {
  const auto* node = impl_->find(key);
  return node && node->is_string();
}

namespace {
std::string show(const toml::node& node) {
  std::ostringstream s;
  node.visit([&](const auto& v) { s << v; });
  return s.str();
}
}  // namespace

double TomlReader::real(const std::string& key, Range range) {
  impl_->consumed.insert(key);
  auto* node = impl_->find(key);
  if (!node) fail(key, "missing; expected a number " + range.describe());
  double v;
  if (auto d = node->value_exact<double>()) v = *d;
  else if (auto i = node->value_exact<int64_t>()) v = static_cast<double>(*i);
  else fail(key, "expected a number, got " + show(*node));
  if (!range.contains(v)) fail(key, "= " + show(*node) + ": expected a number " + range.describe());
  return v;
}

double TomlReader::real(const std::string& key, Range range, double fallback) {
  if (!has(key)) {
    impl_->consumed.insert(key);
    return fallback;
  }
  return real(key, range);
}

long long TomlReader::integer(const std::string& key, long long min, long long max) {
  impl_->consumed.insert(key);
  auto* node = impl_->find(key);
  if (!node) fail(key, "missing; expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  auto i = node->value_exact<int64_t>();
  if (!i) fail(key, "expected an integer, got " + show(*node));
  if (*i < min || *i > max) fail(key, "= " + std::to_string(*i) + ": expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  return *i;
}

long long TomlReader::integer(const std::string& key, long long min, long long max, long long fallback) {
  if (!has(key)) {
    impl_->consumed.insert(key);
    return fallback;
  }
  return integer(key, min, max);
}

bool TomlReader::boolean(const std::string& key, bool fallback) {
  impl_->consumed.insert(key);
  auto* node = impl_->find(key);
  if (!node) return fallback;
  auto b = node->value_exact<bool>();
  if (!b) fail(key, "expected true or false, got " + show(*node));
  return *b;
}

std::string TomlReader::text(const std::string& key, std::optional<std::string> fallback) {
  impl_->consumed.insert(key);
  auto* node = impl_->find(key);
  if (!node) {
    if (fallback) return *fallback;
    fail(key, "missing; expected a string");
  }
  auto s = node->value_exact<std::string>();
  if (!s) fail(key, "expected a string, got " + show(*node));
  return *s;
}

std::string TomlReader::choice(const std::string& key, const std::vector<std::string>& allowed, std::optional<std::string> fallback) {
  const std::string v = text(key, fallback);
  for (const auto& a : allowed)
    if (a == v) return v;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + ("\"" + a + "\"");
  fail(key, "= \"" + v + "\": expected one of " + list);
}

std::vector<double> TomlReader::reals(const std::string& key, Range range, std::optional<std::vector<double>> fallback) {
  impl_->consumed.insert(key);
  auto* node = impl_->find(key);
  if (!node) {
    if (fallback) return *fallback;
    fail(key, "missing; expected an array of numbers");
  }
  auto* array = node->as_array();
  if (!array) fail(key, "expected an array of numbers, got " + show(*node));
  std::vector<double> values;
  for (std::size_t i = 0; i < array->size(); ++i) {
    const auto& item = *array->get(i);
    double v;
    if (auto d = item.value_exact<double>()) v = *d;
    else if (auto n = item.value_exact<int64_t>()) v = static_cast<double>(*n);
    else fail(key, "item " + std::to_string(i + 1) + " is not a number: " + show(item));
    if (!range.contains(v)) fail(key, "item " + std::to_string(i + 1) + " = " + show(item) + ": expected " + range.describe());
    values.push_back(v);
  }
  return values;
}

std::vector<std::string> TomlReader::strings(const std::string& key) {
  impl_->consumed.insert(key);
  auto* node = impl_->find(key);
  if (!node) fail(key, "missing; expected an array of strings");
  auto* array = node->as_array();
  if (!array) fail(key, "expected an array of strings, got " + show(*node));
  std::vector<std::string> values;
  for (std::size_t i = 0; i < array->size(); ++i) {
    const auto& item = *array->get(i);
    auto v = item.value_exact<std::string>();
    if (!v) fail(key, "item " + std::to_string(i + 1) + " is not a string: " + show(item));
    values.push_back(*v);
  }
  return values;
}

std::vector<std::vector<double>> TomlReader::real_rows(const std::string& key, std::size_t width, Range range) {
  impl_->consumed.insert(key);
  auto* node = impl_->find(key);
  if (!node) fail(key, "missing; expected an array of [" + std::to_string(width) + " numbers] rows");
  auto* array = node->as_array();
  if (!array) fail(key, "expected an array of rows, got " + show(*node));
  std::vector<std::vector<double>> rows;
  for (std::size_t i = 0; i < array->size(); ++i) {
    const std::string row_key = key + "." + std::to_string(i);
    auto* row = array->get(i)->as_array();
    if (!row || row->size() != width) fail(row_key, "row " + std::to_string(i + 1) + " must be an array of " + std::to_string(width) + " numbers, got " + show(*array->get(i)));
    std::vector<double> values;
    for (std::size_t j = 0; j < width; ++j) {
      const auto& item = *row->get(j);
      double v;
      if (auto d = item.value_exact<double>()) v = *d;
      else if (auto n = item.value_exact<int64_t>()) v = static_cast<double>(*n);
      else fail(row_key, "row " + std::to_string(i + 1) + ", item " + std::to_string(j + 1) + " is not a number: " + show(item));
      if (!range.contains(v)) fail(row_key, "row " + std::to_string(i + 1) + ", item " + std::to_string(j + 1) + " = " + show(item) + ": expected " + range.describe());
      values.push_back(v);
    }
    rows.push_back(std::move(values));
  }
  return rows;
}

std::size_t TomlReader::table_count(const std::string& key) {
  impl_->consumed.insert(key);
  auto* node = impl_->find(key);
  if (!node) return 0;
  auto* array = node->as_array();
  if (!array || !array->is_array_of_tables()) fail(key, "expected an array of tables ([[" + key + "]])");
  return array->size();
}

void TomlReader::finish() const {
  // Depth-first over the document; a key is known if it or one of its parents was consumed as a leaf.
  std::function<void(const toml::node&, const std::string&)> walk = [&](const toml::node& node, const std::string& path) {
    if (!path.empty() && impl_->consumed.count(path) && !node.is_table() && !node.is_array_of_tables()) return;
    if (auto* t = node.as_table()) {
      for (const auto& [k, v] : *t) walk(v, path.empty() ? std::string(k.str()) : path + "." + std::string(k.str()));
      return;
    }
    if (auto* a = node.as_array(); a && a->is_array_of_tables() && impl_->consumed.count(path)) {
      for (std::size_t i = 0; i < a->size(); ++i) walk(*a->get(i), path + "." + std::to_string(i));
      return;
    }
    if (!impl_->consumed.count(path)) fail(path, "unknown key (see docs/case-files.md for the keys each section accepts)");
  };
  walk(impl_->root, "");
}

std::string TomlReader::resolved_text() const {
  std::ostringstream s;
  s << toml::toml_formatter{impl_->root};
  return s.str();
}

std::string case_text_without(const std::string& text, const std::vector<std::string>& tables, const std::vector<std::string>& path_keys,
                              const std::string& base) {
  toml::table root = toml::parse(text);
  for (const auto& t : tables) root.erase(t);
  for (const auto& key : path_keys) {
    const auto dot = key.find('.');
    auto* table = root[key.substr(0, dot)].as_table();
    if (!table) continue;
    auto* value = (*table)[key.substr(dot + 1)].as_string();
    if (!value) continue;
    std::filesystem::path p(value->get());
    if (p.is_relative() && !base.empty() && base.front() != '<') *value = (std::filesystem::absolute(std::filesystem::path(base).parent_path()) / p).lexically_normal().string();
  }
  std::ostringstream s;
  s << toml::toml_formatter{root};
  return s.str() + "\n";
}

}  // namespace drom
