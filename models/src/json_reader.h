#pragma once
// A small typed reader of JSON input files (comments allowed) that knows
// the path of every value, marks every key it reads and rejects the keys
// nobody read: the scene reader's and the dataset spec reader's. Errors
// read "FILE: key.path = VALUE: rule". Internal to models.

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "purkinje/models/check.h"
#include "purkinje/models/geometry.h"
#include "purkinje/models/spelling.h"

namespace purkinje::json_reader {

using json = nlohmann::json;
using check::format_number;

// What the reader throws; each file format turns it into its own error.
class JsonFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Positions far beyond any tracker would only overflow squared distances.
constexpr double kMaxCoordinateMm = 1e6;


// A value as the user wrote it, short enough for one line of a message.
std::string format_value(const json& v, int depth = 0);

std::string format_point(const Point3& p);

std::string join(const std::vector<std::string>& items);

// Where a value lives in the file: the source's name and the key path.
struct Location {
  const std::string* source;
  std::string path;

  Location child(std::string_view key) const {
    return {source, path.empty() ? std::string(key) : path + "." + std::string(key)};
  }
  Location element(std::size_t i) const { return {source, path + "[" + std::to_string(i) + "]"}; }

  // "FILE: path = VALUE: rule"; `value_text` empty for a key with no value.
  [[noreturn]] void fail(const std::string& value_text, const std::string& rule) const {
    std::string message = *source + ": " + (path.empty() ? "(top level)" : path);
    if (!value_text.empty()) message += " = " + value_text;
    throw JsonFileError(message + ": " + rule);
  }
  [[noreturn]] void fail_number(double value, const std::string& rule) const {
    fail(format_number(value), rule);
  }
};

// One JSON value and its location, with typed conversions that fail with
// the path, the value and the expected type.
class Value {
 public:
  Value(const json& j, Location where) : j_(&j), where_(std::move(where)) {}

  const json& raw() const { return *j_; }
  const Location& where() const { return where_; }
  [[noreturn]] void fail(const std::string& rule) const { where_.fail(format_value(*j_), rule); }

  double as_double() const {
    if (!j_->is_number()) fail("must be a number");
    const double v = j_->get<double>();
    if (!std::isfinite(v)) fail("must be a finite number");
    return v;
  }
  int as_int() const {
    if (j_->is_number_unsigned()) {
      if (j_->get<std::uint64_t>() > static_cast<std::uint64_t>(INT_MAX)) fail("is too large");
      return static_cast<int>(j_->get<std::uint64_t>());
    }
    if (j_->is_number_integer()) {
      const auto v = j_->get<std::int64_t>();
      if (v < INT_MIN || v > INT_MAX) fail("is out of range");
      return static_cast<int>(v);
    }
    const double v = as_double();
    if (v != std::floor(v)) fail("must be an integer");
    if (v < INT_MIN || v > INT_MAX) fail("is out of range");
    return static_cast<int>(v);
  }
  std::string as_string() const {
    if (!j_->is_string()) fail("must be a string");
    return j_->get<std::string>();
  }
  bool as_bool() const {
    if (!j_->is_boolean()) fail("must be true or false");
    return j_->get<bool>();
  }
  // A non-negative integer below 2^53: larger ones would not survive a
  // reader that keeps JSON numbers as doubles (Python's json does not, but
  // JavaScript and many others do), so a seed could silently change.
  std::uint64_t as_exact_count() const {
    constexpr std::uint64_t kLimit = std::uint64_t{1} << 53;
    std::uint64_t v = 0;
    if (j_->is_number_unsigned()) {
      v = j_->get<std::uint64_t>();
    } else if (j_->is_number_integer()) {
      if (j_->get<std::int64_t>() < 0) fail("must be >= 0");
      v = static_cast<std::uint64_t>(j_->get<std::int64_t>());
    } else {
      const double d = as_double();
      if (d != std::floor(d)) fail("must be an integer");
      if (d < 0) fail("must be >= 0");
      if (d >= static_cast<double>(kLimit)) v = kLimit;
      else v = static_cast<std::uint64_t>(d);
    }
    if (v >= kLimit) {
      fail("must be < 2^53 = 9007199254740992 (larger integers are not exact in many JSON readers)");
    }
    return v;
  }
  std::vector<Value> elements() const {
    if (!j_->is_array()) fail("must be an array");
    std::vector<Value> out;
    for (std::size_t i = 0; i < j_->size(); ++i) out.emplace_back((*j_)[i], where_.element(i));
    return out;
  }
  std::vector<double> as_numbers(std::size_t count) const {
    const std::string rule = "must be an array of " + std::to_string(count) + " numbers";
    if (!j_->is_array() || j_->size() != count) fail(rule);
    std::vector<double> out;
    for (const Value& e : elements()) out.push_back(e.as_double());
    return out;
  }
  // Positions far beyond any tracker would only overflow squared distances.
  Point3 as_point3() const {
    const auto v = bounded_triple();
    return {v[0], v[1], v[2]};
  }
  Vector3 as_vector3() const {
    const auto v = bounded_triple();
    return {v[0], v[1], v[2]};
  }

  // Range rules, naming the value.
  double positive() const {
    const double v = as_double();
    if (!(v > 0)) fail("must be > 0");
    return v;
  }
  double non_negative() const {
    const double v = as_double();
    if (!(v >= 0)) fail("must be >= 0");
    return v;
  }
  // Conicoids with Q < -1 are hyperboloids, open toward the eye's inside;
  // the solver's inside/outside test assumes a closed surface.
  double asphericity() const {
    const double v = as_double();
    if (!(v >= -1.0)) fail("must be >= -1 (hyperboloidal corneas are not modelled)");
    return v;
  }
  double refractive_index() const {
    const double v = as_double();
    if (!(v >= 1)) fail("must be >= 1 (a refractive index)");
    return v;
  }
  std::vector<double> bounded_triple() const {
    const auto v = as_numbers(3);
    for (double c : v) {
      if (std::abs(c) > kMaxCoordinateMm) {
        fail("coordinates must be within +-" + format_number(kMaxCoordinateMm) + " (1 km in mm)");
      }
    }
    return v;
  }
  double within(double low, double high) const {
    const double v = as_double();
    if (!(v >= low && v <= high)) {
      fail("must be between " + format_number(low) + " and " + format_number(high));
    }
    return v;
  }
  // A direction given as [x, y, z]: any non-zero length.
  Vector3 direction() const {
    const Vector3 v = as_vector3();
    if (!(v.norm() > 0)) fail("must not be the zero vector");
    return v;
  }

 private:
  const json* j_;
  Location where_;
};

// A JSON object whose keys are read by name. Every key asked about (even
// through has()) is known; finish() rejects the keys nobody asked about.
class Object {
 public:
  explicit Object(const Value& v) : self_(v) {
    if (!v.raw().is_object()) v.fail("must be an object");
  }

  const Location& where() const { return self_.where(); }

  bool has(const std::string& key) {
    known_.insert(key);
    return self_.raw().contains(key);
  }
  std::optional<Value> optional(const std::string& key) {
    if (!has(key)) return std::nullopt;
    return Value(self_.raw().at(key), where().child(key));
  }
  Value required(const std::string& key, const std::string& what = "") {
    if (auto v = optional(key)) return *v;
    std::string rule = "missing required key";
    if (!what.empty()) rule += " (" + what + ")";
    where().child(key).fail("", rule + misspelling_hint({key}));
  }
  Object object(const std::string& key) { return Object(required(key)); }
  std::optional<Object> optional_object(const std::string& key) {
    if (auto v = optional(key)) return Object(*v);
    return std::nullopt;
  }

  // Typed reads: get<double>("radius_mm") for a required key, get_or for
  // an optional one. The type's own rule (finite number, integer, three
  // coordinates, ...) is checked; range rules follow below.
  template <class T>
  T get(const std::string& key) {
    return convert<T>(required(key));
  }
  template <class T>
  T get_or(const std::string& key, const T& fallback) {
    if (auto v = optional(key)) return convert<T>(*v);
    return fallback;
  }

  // Optional numbers with a default, range-checked when present.
  double positive_or(const std::string& key, double fallback) {
    if (auto v = optional(key)) return v->positive();
    return fallback;
  }
  double non_negative_or(const std::string& key, double fallback) {
    if (auto v = optional(key)) return v->non_negative();
    return fallback;
  }
  double within_or(const std::string& key, double low, double high, double fallback) {
    if (auto v = optional(key)) return v->within(low, high);
    return fallback;
  }

  // Exactly one of `a` and `b`; returns true for `a`.
  bool one_of(const std::string& a, const std::string& b) { return one_of({a, b}) == 0; }
  // Exactly one of `keys` (two or more); returns its index.
  std::size_t one_of(const std::vector<std::string>& keys) {
    std::vector<std::size_t> present;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (has(keys[i])) present.push_back(i);
    }
    std::string listed;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      listed += (i == 0 ? "" : i + 1 == keys.size() ? " and " : ", ") + keys[i];
    }
    if (present.size() > 1) {
      where().fail("", "give exactly one of " + listed + (keys.size() == 2 ? ", not both" : ", not several"));
    }
    if (present.empty()) {
      where().fail("", "missing required key: give one of " + listed + misspelling_hint(keys));
    }
    return present.front();
  }

  void finish() const {
    for (const auto& [key, value] : self_.raw().items()) {
      if (known_.count(key)) continue;
      std::vector<std::string> valid(known_.begin(), known_.end());
      Value(value, where().child(key)).fail("unknown key (valid keys here: " + join(valid) + ")");
    }
  }

 private:
  // "; found \"positon\"" when an unread key here looks like a wanted one,
  // so that a typo is reported as such and not only as a missing key.
  std::string misspelling_hint(const std::vector<std::string>& wanted) const {
    std::vector<std::string> similar;
    for (const auto& [key, value] : self_.raw().items()) {
      if (known_.count(key)) continue;
      for (const auto& w : wanted) {
        if (looks_like(key, w)) {
          similar.push_back("\"" + key + "\"");
          break;
        }
      }
    }
    return similar.empty() ? "" : "; found " + join(similar) + " (misspelt?)";
  }

  template <class T>
  static T convert(const Value& v) {
    if constexpr (std::is_same_v<T, double>) return v.as_double();
    else if constexpr (std::is_same_v<T, int>) return v.as_int();
    else if constexpr (std::is_same_v<T, std::string>) return v.as_string();
    else if constexpr (std::is_same_v<T, bool>) return v.as_bool();
    else if constexpr (std::is_same_v<T, Point3>) return v.as_point3();
    else if constexpr (std::is_same_v<T, Vector3>) return v.as_vector3();
    else static_assert(sizeof(T) == 0, "no conversion from JSON to this type");
  }

  Value self_;
  std::set<std::string> known_;
};

// Runs `read` for the object at `where`, turning a model's own complaint
// (std::invalid_argument from a constructor) into a SceneError there. The
// reader's checks should leave nothing for the model to reject; this keeps
// load_scene's promise of SceneError if one slips through.
template <class Read>
auto located(const Location& where, Read read) {
  try {
    return read();
  } catch (const std::invalid_argument& error) {
    where.fail("", error.what());
  }
}

// Objects of a required, non-empty (unless `may_be_empty`) array.
std::vector<Value> read_list(Object& root, const std::string& key, bool required);

// Duplicate keys: JSON leaves them undefined and nlohmann keeps the last,
// which would silently drop a value the user wrote.
json parse_json(const std::string& text, const std::string& source);


}  // namespace purkinje::json_reader
