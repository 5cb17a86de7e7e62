#include "json_reader.h"

namespace purkinje::json_reader {

std::string format_value(const json& v, int depth) {
  std::string text;
  // Bounded recursion: a scene nested thousands of levels deep must get a
  // message, not a stack overflow.
  if (depth >= 3 && (v.is_array() || v.is_object())) return v.is_array() ? "[...]" : "{...}";
  switch (v.type()) {
    case json::value_t::number_float: text = format_number(v.get<double>()); break;
    case json::value_t::array: {
      text = "[";
      for (std::size_t i = 0; i < v.size(); ++i) {
        if (i > 0) text += ", ";
        if (i == 8) {
          text += "...";
          break;
        }
        text += format_value(v[i], depth + 1);
      }
      text += "]";
      break;
    }
    case json::value_t::object: text = v.empty() ? "{}" : "{...}"; break;
    default: text = v.dump(); break;
  }
  if (text.size() > 80) text = text.substr(0, 77) + "...";
  return text;
}

// Appended (g++ 12's false -Wrestrict on "[" + std::string, its bug 105329).
std::string format_point(const Point3& p) {
  std::string text = "[";
  for (const double x : {p.x, p.y, p.z}) {
    if (text.size() > 1) text += ", ";
    text += format_number(x);
  }
  text += "]";
  return text;
}

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

std::vector<Value> read_list(Object& root, const std::string& key, bool required) {
  std::optional<Value> list = required ? std::optional<Value>(root.required(key)) : root.optional(key);
  if (!list) return {};
  auto items = list->elements();
  if (required && items.empty()) list->fail("must list at least one entry");
  return items;
}

json parse_json(const std::string& text, const std::string& source) {
  std::vector<std::set<std::string>> open_objects;
  std::optional<std::string> duplicate;
  const json::parser_callback_t check_duplicates = [&](int, json::parse_event_t event, json& parsed) {
    if (event == json::parse_event_t::object_start) open_objects.emplace_back();
    if (event == json::parse_event_t::object_end && !open_objects.empty()) open_objects.pop_back();
    if (event == json::parse_event_t::key && !open_objects.empty() && !duplicate) {
      const auto key = parsed.get<std::string>();
      if (!open_objects.back().insert(key).second) duplicate = key;
    }
    return true;
  };
  json root;
  try {
    root = json::parse(text, check_duplicates, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const json::parse_error& error) {
    // what() reads "[json.exception.parse_error.101] parse error at line L, column C: ...".
    std::string what = error.what();
    if (const auto bracket = what.find("] "); bracket != std::string::npos) what = what.substr(bracket + 2);
    throw JsonFileError(source + ": invalid JSON (byte " + std::to_string(error.byte) + "): " + what);
  } catch (const json::exception& error) {
    // Number overflow (1e999) and the like carry no position; find the line.
    std::string what = error.what();
    if (const auto bracket = what.find("] "); bracket != std::string::npos) what = what.substr(bracket + 2);
    std::string where;
    if (const auto quote = what.find('\''); quote != std::string::npos) {
      const auto end = what.find('\'', quote + 1);
      const auto token = what.substr(quote + 1, end - quote - 1);
      if (const auto at = text.find(token); !token.empty() && at != std::string::npos) {
        where = " at line " + std::to_string(1 + std::count(text.begin(), text.begin() + at, '\n'));
      }
    }
    throw JsonFileError(source + ": invalid JSON" + where + ": " + what);
  }
  if (duplicate) throw JsonFileError(source + ": invalid JSON: duplicate key \"" + *duplicate + "\"");
  return root;
}

}  // namespace purkinje::json_reader
