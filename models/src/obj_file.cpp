// Wavefront OBJ: a strict reader of the polygon subset (see obj_file.h).
// Every statement is checked where it is read, so that a message can name
// its line; face indices may point forward, so their range, and the
// polygons' shape, are checked once every vertex is known.

#include "purkinje/models/obj_file.h"

#include "purkinje/models/input_file.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <system_error>

namespace purkinje {
namespace {

// Embree and the Mesh store 32-bit indices.
constexpr std::size_t kMaxVertices = std::numeric_limits<std::uint32_t>::max();
// A triangle whose sides meet at a sine below this is a line to rounding:
// it has no area to shade, and its orientation is noise.
constexpr double kDegenerateSine = 1e-12;

// A token as one line of a message can show it: quoted, control and
// non-ASCII bytes escaped (a binary file must not garble the terminal),
// long ones cut.
std::string shown(std::string_view token) {
  constexpr std::size_t kMax = 24;
  std::string out = "\"";
  for (char c : token.substr(0, kMax)) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7f && c != '"' && c != '\\') {
      out += c;
    } else {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", byte);
      out += escaped;
    }
  }
  if (token.size() > kMax) out += "...";
  return out + "\"";
}

[[noreturn]] void fail(std::size_t line, const std::string& what) {
  throw ObjError("line " + std::to_string(line) + ": " + what);
}

std::vector<std::string_view> split(std::string_view text, std::string_view separators) {
  std::vector<std::string_view> out;
  std::size_t start = text.find_first_not_of(separators);
  while (start != std::string_view::npos) {
    const std::size_t end = text.find_first_of(separators, start);
    out.push_back(text.substr(start, end == std::string_view::npos ? end : end - start));
    start = end == std::string_view::npos ? end : text.find_first_not_of(separators, end);
  }
  return out;
}

// from_chars refuses a leading '+', which some exporters write.
std::string_view without_plus(std::string_view token) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '+' && token[1] != '-') token.remove_prefix(1);
  return token;
}

double coordinate(std::string_view token, std::size_t line) {
  const std::string_view digits = without_plus(token);
  double value = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (end != digits.data() + digits.size() ||
      (error != std::errc() && error != std::errc::result_out_of_range)) {
    fail(line, "vertex coordinate " + shown(token) + " is not a number");
  }
  if (error == std::errc::result_out_of_range) {
    fail(line, "vertex coordinate " + shown(token) + " is out of the range of double precision");
  }
  if (!std::isfinite(value)) fail(line, "vertex coordinate " + shown(token) + " is not a finite number");
  return value;
}

// An index as written: a non-zero integer (OBJ counts from 1; negative
// counts back from the last element read so far).
std::int64_t index_as_written(std::string_view token, std::string_view what, std::string_view reference,
                              std::size_t line) {
  const std::string_view digits = without_plus(token);
  std::int64_t value = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (error != std::errc() || end != digits.data() + digits.size()) {
    fail(line, std::string(what) + " index " + shown(token) + " in " + shown(reference) +
                   " is not an integer");
  }
  if (value == 0) fail(line, std::string(what) + " index 0 in " + shown(reference) + ": OBJ indices start at 1");
  return value;
}

// One `f` statement: vertex indices resolved to 0-based ones, except that
// positive ones may still exceed the vertex count (forward references).
struct Face {
  std::size_t line = 0;
  std::vector<std::int64_t> written;   // as in the file, for messages
  std::vector<std::int64_t> resolved;  // 0-based
};

class Reader {
 public:
  void statement(std::string_view text, std::size_t line) {
    const auto tokens = split(text, " \t\v\f");
    if (tokens.empty()) return;
    const std::string_view keyword = tokens[0];
    if (keyword == "v") return vertex(tokens, line);
    if (keyword == "f") return face(tokens, line);
    static const std::set<std::string_view> skipped = {
        // Texture coordinates and normals: shading uses each triangle's
        // own plane, and a face's references to them are checked for syntax.
        "vt", "vn",
        // Grouping, materials and display attributes: nothing geometric.
        "o", "g", "s", "mg", "usemtl", "mtllib", "usemap", "maplib", "lod", "bevel", "c_interp",
        "d_interp", "shadow_obj", "trace_obj",
        // Lines, points and free-form parameter vertices have no area.
        "l", "p", "vp"};
    if (skipped.count(keyword)) return;
    static const std::set<std::string_view> free_form = {
        "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm", "trim",
        "hole", "scrv", "sp", "end", "con", "ctech", "stech"};
    if (free_form.count(keyword)) {
      fail(line, shown(keyword) + " (free-form geometry) is not supported: export the mesh as polygons");
    }
    if (keyword == "call" || keyword == "csh") {
      fail(line, shown(keyword) + " (reading another file or running a command) is not supported");
    }
    fail(line, "unknown statement " + shown(keyword) + " (expected v, vt, vn, f, o, g, s, usemtl, mtllib, l or #)");
  }

  ObjMesh finish() {
    if (faces_.empty()) throw ObjError("no faces (no \"f\" statement)");
    const std::size_t count = mesh_.vertices.size();
    for (const Face& f : faces_) {
      for (std::size_t i = 0; i < f.resolved.size(); ++i) {
        if (f.resolved[i] >= static_cast<std::int64_t>(count)) {
          fail(f.line, "face index " + std::to_string(f.written[i]) + " out of range (file has " +
                           std::to_string(count) + " vertices)");
        }
      }
      triangulate(f);
    }
    if (mesh_.triangles.empty()) {
      throw ObjError("all " + std::to_string(faces_.size()) + " faces have zero area");
    }
    return std::move(mesh_);
  }

 private:
  void vertex(const std::vector<std::string_view>& tokens, std::size_t line) {
    // x y z, with an optional weight w (meaningful for rational curves
    // only) or an r g b colour (a common extension); both ignored.
    const std::size_t numbers = tokens.size() - 1;
    if (numbers != 3 && numbers != 4 && numbers != 6) {
      fail(line, "vertex has " + std::to_string(numbers) + " numbers (expected x y z, optionally w or r g b)");
    }
    double xyz[3];
    for (std::size_t i = 1; i < tokens.size(); ++i) {
      const double v = coordinate(tokens[i], line);
      if (i <= 3) xyz[i - 1] = v;
    }
    if (mesh_.vertices.size() >= kMaxVertices) fail(line, "more than 2^32 - 1 vertices");
    mesh_.vertices.push_back({xyz[0], xyz[1], xyz[2]});
  }

  void face(const std::vector<std::string_view>& tokens, std::size_t line) {
    Face f;
    f.line = line;
    for (std::size_t i = 1; i < tokens.size(); ++i) {
      // v, v/vt, v//vn or v/vt/vn.
      const auto parts = split_reference(tokens[i]);
      if (parts.size() > 3 || parts[0].empty()) {
        fail(line, "vertex reference " + shown(tokens[i]) + " is not v, v/vt, v//vn or v/vt/vn");
      }
      const std::int64_t v = index_as_written(parts[0], "vertex", tokens[i], line);
      if (parts.size() > 1 && !parts[1].empty()) index_as_written(parts[1], "texture", tokens[i], line);
      if (parts.size() > 2) index_as_written(parts[2], "normal", tokens[i], line);
      const auto before = static_cast<std::int64_t>(mesh_.vertices.size());
      if (v < 0 && before + v < 0) {
        fail(line, "face index " + std::to_string(v) + " out of range (" + std::to_string(before) +
                       " vertices before this line)");
      }
      f.written.push_back(v);
      f.resolved.push_back(v < 0 ? before + v : v - 1);
    }
    if (f.resolved.size() < 3) {
      fail(line, "face has " + std::to_string(f.resolved.size()) + " vertices (at least 3 needed)");
    }
    faces_.push_back(std::move(f));
  }

  // Split on '/', keeping empty parts ("1//3" is 1, "", 3).
  static std::vector<std::string_view> split_reference(std::string_view token) {
    std::vector<std::string_view> parts;
    std::size_t start = 0;
    while (true) {
      const std::size_t slash = token.find('/', start);
      parts.push_back(token.substr(start, slash == std::string_view::npos ? slash : slash - start));
      if (slash == std::string_view::npos) return parts;
      start = slash + 1;
    }
  }

  // A fan from the first vertex, exact for convex polygons. A fan triangle
  // turning against the polygon's own orientation (the sum of the fan's
  // area vectors) folds over the rest: the polygon is not convex, and the
  // fan would be a different surface.
  void triangulate(const Face& f) {
    const auto& v = mesh_.vertices;
    const Point3& p0 = v[f.resolved[0]];
    std::vector<Vector3> areas;
    Vector3 total;
    for (std::size_t i = 1; i + 1 < f.resolved.size(); ++i) {
      const Vector3 a = v[f.resolved[i]] - p0, b = v[f.resolved[i + 1]] - p0;
      const Vector3 n = cross(a, b);
      areas.push_back(n.norm() > kDegenerateSine * a.norm() * b.norm() ? n : Vector3{});
      total += areas.back();
    }
    for (std::size_t i = 0; i < areas.size(); ++i) {
      if (areas[i] == Vector3{}) continue;  // no area: nothing to draw
      if (!(dot(areas[i], total) > 0)) {
        fail(f.line, "polygon of " + std::to_string(f.resolved.size()) +
                         " vertices is not convex (split from its first vertex it would fold over "
                         "itself): triangulate it when exporting");
      }
      mesh_.triangles.push_back({static_cast<std::uint32_t>(f.resolved[0]),
                                 static_cast<std::uint32_t>(f.resolved[i + 1]),
                                 static_cast<std::uint32_t>(f.resolved[i + 2])});
    }
  }

  ObjMesh mesh_;
  std::vector<Face> faces_;
};

}  // namespace

ObjMesh parse_obj(std::string_view text) {
  Reader reader;
  std::string statement;  // a statement may continue over lines ending in '\'
  std::size_t statement_line = 0;
  std::size_t line_number = 0;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    start = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    if (statement.empty()) statement_line = line_number;
    if (!line.empty() && line.back() == '\\') {
      line.remove_suffix(1);
      statement.append(line).append(" ");
      continue;
    }
    statement.append(line);
    reader.statement(statement, statement_line);
    statement.clear();
  }
  if (!statement.empty()) reader.statement(statement, statement_line);
  return reader.finish();
}

ObjMesh load_obj(const std::filesystem::path& file) {
  std::string text;
  try {
    text = read_input_file(file, kMaxMeshFileBytes, "an OBJ file");
  } catch (const InputFileError& e) {
    throw ObjError(e.reason());
  }
  return parse_obj(text);
}

}  // namespace purkinje
