#pragma once
// Typed, validated access to a TOML input (case files, machine files). Every accessor records the key it read; finish()
// then rejects any key nobody asked for, so a typo is an error rather than a silent default.
// Errors are InputError naming the file, the line and the dotted key.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace drom {

struct Range {
  double min = -1e300, max = 1e300;
  bool min_exclusive = false, max_exclusive = false;
  static Range positive() { return {0, 1e300, true, false}; }
  static Range non_negative() { return {0, 1e300, false, false}; }
  static Range closed(double a, double b) { return {a, b, false, false}; }
  static Range open_closed(double a, double b) { return {a, b, true, false}; }
  static Range open(double a, double b) { return {a, b, true, true}; }
  std::string describe() const;
  bool contains(double v) const;
};

class TomlReader {
 public:
  // `origin` names the text in messages (a path, or "<embedded default case>").
  TomlReader(const std::string& text, std::string origin);
  // The one way every case reader opens its input: the text, then the `--set` overrides in order.
  TomlReader(const std::string& text, std::string origin, const std::vector<std::string>& overrides);
  ~TomlReader();
  TomlReader(const TomlReader&) = delete;
  TomlReader& operator=(const TomlReader&) = delete;

  // Applies one "dotted.key=value" override. The value is read as TOML ("3", "[1, 2]", "'x'"),
  // or as a bare string when it is not valid TOML. Unknown keys are caught by finish().
  void apply_override(const std::string& assignment);

  bool has(const std::string& key) const;
  // The key is present and holds a string (for keys that take a number or a word such as "auto").
  bool is_text(const std::string& key) const;
  double real(const std::string& key, Range range);
  double real(const std::string& key, Range range, double fallback);
  long long integer(const std::string& key, long long min, long long max);
  long long integer(const std::string& key, long long min, long long max, long long fallback);
  bool boolean(const std::string& key, bool fallback);
  std::string text(const std::string& key, std::optional<std::string> fallback = std::nullopt);
  std::string choice(const std::string& key, const std::vector<std::string>& allowed, std::optional<std::string> fallback = std::nullopt);
  std::vector<double> reals(const std::string& key, Range range, std::optional<std::vector<double>> fallback = std::nullopt);
  std::vector<std::string> strings(const std::string& key);
  // An array of arrays of numbers, each of `width` numbers ([[x, y, z], ...]); a bad row's error names
  // its own line.
  std::vector<std::vector<double>> real_rows(const std::string& key, std::size_t width, Range range);
  // Number of tables in an array of tables ([[name]]); 0 when absent.
  std::size_t table_count(const std::string& key);

  // Throws on the first key present in the file that no accessor read.
  void finish() const;
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;
  // Where a key was given, as fail() names it: "file:line: key", "file: key" or "--set key"; for
  // errors found after reading (a run that finds the value unusable).
  std::string where(const std::string& key) const;
  const std::string& origin() const { return origin_; }
  // The case after overrides, as TOML (for summaries and for the offline database).
  std::string resolved_text() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string origin_;
};

// A case, machine or settings file's text; InputError "PATH: cannot open the WHAT (missing or
// unreadable)" otherwise. With TomlReader(text, path, overrides), what every case reader opens.
std::string read_input_file(const std::filesystem::path& path, const std::string& what);

// `text` (TOML) without the named top-level tables, with the named string keys (dotted) made absolute
// paths relative to `base` (so the text can be written elsewhere). Deterministic: the same input
// gives the same bytes.
std::string case_text_without(const std::string& text, const std::vector<std::string>& tables, const std::vector<std::string>& path_keys,
                              const std::string& base);

}  // namespace drom
