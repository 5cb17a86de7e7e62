#include "purkinje/models/obj_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>

namespace purkinje {
namespace {

namespace fs = std::filesystem;

const fs::path kSourceDir = PURKINJE_SOURCE_DIR;

// The message of the ObjError that parsing `text` throws; "" if none.
std::string obj_error(const std::string& text) {
  try {
    parse_obj(text);
  } catch (const ObjError& e) {
    return e.what();
  }
  return "";
}

constexpr const char* kTriangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

TEST(ObjFile, ReadsATriangleInItsWindingOrder) {
  const ObjMesh mesh = parse_obj(std::string(kTriangle) + "f 1 2 3\n");
  ASSERT_EQ(mesh.vertices.size(), 3u);
  EXPECT_EQ(mesh.vertices[1], Point3(1, 0, 0));
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.triangles[0], (Triangle{0, 1, 2}));
}

TEST(ObjFile, SplitsAConvexPolygonIntoAFanFromItsFirstVertex) {
  // A pentagon: three triangles (0 1 2), (0 2 3), (0 3 4).
  const ObjMesh mesh = parse_obj("v 0 0 0\nv 2 0 0\nv 3 1 0\nv 1 3 0\nv -1 1 0\nf 1 2 3 4 5\n");
  ASSERT_EQ(mesh.triangles.size(), 3u);
  EXPECT_EQ(mesh.triangles[0], (Triangle{0, 1, 2}));
  EXPECT_EQ(mesh.triangles[1], (Triangle{0, 2, 3}));
  EXPECT_EQ(mesh.triangles[2], (Triangle{0, 3, 4}));
}

TEST(ObjFile, LeavesOutTrianglesWithoutArea) {
  // A square with a vertex in the middle of its bottom edge: the fan's
  // first triangle (0 1 2) is a line.
  const ObjMesh mesh = parse_obj("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nf 1 2 3 4 5\n");
  ASSERT_EQ(mesh.triangles.size(), 2u);
  EXPECT_EQ(mesh.triangles[0], (Triangle{0, 2, 3}));
  EXPECT_EQ(mesh.triangles[1], (Triangle{0, 3, 4}));
  // A face repeating a vertex has no area either.
  EXPECT_EQ(parse_obj(std::string(kTriangle) + "f 1 2 3\nf 1 1 2\n").triangles.size(), 1u);
}

TEST(ObjFile, AcceptsEveryIndexFormAndNegativeIndices) {
  const std::string head = std::string(kTriangle) + "vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n";
  for (const char* face : {"f 1 2 3", "f 1/1 2/2 3/3", "f 1//1 2//1 3//1", "f 1/1/1 2/2/1 3/3/1",
                           "f -3 -2 -1", "f -3/-3/-1 -2/-2/-1 -1/-1/-1", "f +1 +2 +3"}) {
    const ObjMesh mesh = parse_obj(head + face + "\n");
    ASSERT_EQ(mesh.triangles.size(), 1u) << face;
    EXPECT_EQ(mesh.triangles[0], (Triangle{0, 1, 2})) << face;
  }
}

TEST(ObjFile, NegativeIndicesCountBackFromTheLineTheyAreOn) {
  // -1 is the vertex just read, not the file's last.
  const ObjMesh mesh = parse_obj(std::string(kTriangle) + "f -3 -2 -1\nv 5 5 5\nv 6 5 5\nf -1 -2 1\n");
  ASSERT_EQ(mesh.triangles.size(), 2u);
  EXPECT_EQ(mesh.triangles[1], (Triangle{4, 3, 0}));
}

TEST(ObjFile, FacesMayComeBeforeTheirVertices) {
  const ObjMesh mesh = parse_obj(std::string("f 1 2 3\n") + kTriangle);
  EXPECT_EQ(mesh.triangles.size(), 1u);
}

TEST(ObjFile, ReadsWhatExportersWrite) {
  // Blender-style header, CRLF line ends, comments after statements, a
  // statement continued over two lines, vertex weights and colours,
  // materials, groups, smoothing, lines and points.
  const std::string text =
      "# Blender 3.6.0\r\nmtllib frame.mtl\r\no Frame\r\n"
      "v 0.0 0.0 0.0 1.0\r\n"
      "v 1.5e0 0 0 0.2 0.3 0.4\r\n"
      "v \\\r\n 0 +1 -0  # a comment\r\n"
      "vt 0.5 0.5\r\nvn 0 0 1\r\ng rim\r\nusemtl plastic\r\ns off\r\n"
      "f 1/1/1 2/1/1 3/1/1\r\nl 1 2\r\np 3\r\n";
  const ObjMesh mesh = parse_obj(text);
  ASSERT_EQ(mesh.vertices.size(), 3u);
  EXPECT_EQ(mesh.vertices[1], Point3(1.5, 0, 0));
  EXPECT_EQ(mesh.vertices[2], Point3(0, 1, 0));
  EXPECT_EQ(mesh.triangles.size(), 1u);
}

TEST(ObjFile, ConcavePolygonFannedFromItsReflexVertexIsAccepted) {
  // An arrowhead (dart) whose reflex vertex (2, 1) comes first: every fan
  // triangle turns the same way.
  const ObjMesh mesh = parse_obj("v 2 1 0\nv 4 0 0\nv 2 3 0\nv 0 0 0\nf 1 2 3 4\n");
  EXPECT_EQ(mesh.triangles.size(), 2u);
}

TEST(ObjFile, EveryMistakeNamesItsLineAndTheRule) {
  const std::map<std::string, std::string> bad = {
      {"hello world\n", "line 1: unknown statement \"hello\" (expected v, vt, vn, f, o, g, s, usemtl, "
                        "mtllib, l or #)"},
      {std::string(kTriangle) + "f 1 2 40\n", "line 4: face index 40 out of range (file has 3 vertices)"},
      {std::string(kTriangle) + "f 1 2 -9\n",
       "line 4: face index -9 out of range (3 vertices before this line)"},
      {"v 1 nan 0\n", "line 1: vertex coordinate \"nan\" is not a finite number"},
      {"v 1 -inf 0\n", "line 1: vertex coordinate \"-inf\" is not a finite number"},
      {"v 1 1e999 0\n", "line 1: vertex coordinate \"1e999\" is out of the range of double precision"},
      {"\nv 1 abc 0\n", "line 2: vertex coordinate \"abc\" is not a number"},
      {"v 1 2.5.1 0\n", "line 1: vertex coordinate \"2.5.1\" is not a number"},
      {"v 1 0\n", "line 1: vertex has 2 numbers (expected x y z, optionally w or r g b)"},
      {"v 1 0 0 1 1\n", "line 1: vertex has 5 numbers"},
      {std::string(kTriangle) + "f 1 2 0\n", "line 4: vertex index 0 in \"0\": OBJ indices start at 1"},
      {std::string(kTriangle) + "f 1 2 x\n", "line 4: vertex index \"x\" in \"x\" is not an integer"},
      {std::string(kTriangle) + "f 1 2 3.0\n", "line 4: vertex index \"3.0\" in \"3.0\" is not an integer"},
      {std::string(kTriangle) + "f 1 2 3/a\n", "line 4: texture index \"a\" in \"3/a\" is not an integer"},
      {std::string(kTriangle) + "f 1 2 3//\n", "line 4: normal index \"\" in \"3//\" is not an integer"},
      {std::string(kTriangle) + "f 1 2 3/1/1/1\n",
       "line 4: vertex reference \"3/1/1/1\" is not v, v/vt, v//vn or v/vt/vn"},
      {std::string(kTriangle) + "f 1 2 /3\n", "line 4: vertex reference \"/3\" is not v, v/vt"},
      {std::string(kTriangle) + "f 1 2\n", "line 4: face has 2 vertices (at least 3 needed)"},
      {"curv 0 1 1 2\n", "line 1: \"curv\" (free-form geometry) is not supported: export the mesh as polygons"},
      {"call other.obj\n", "line 1: \"call\" (reading another file or running a command) is not supported"},
      // A dart whose first vertex is convex: the fan folds over the reflex one.
      {"v 0 0 0\nv 2 1 0\nv 4 0 0\nv 2 3 0\nf 1 2 3 4\n",
       "line 5: polygon of 4 vertices is not convex (split from its first vertex it would fold over "
       "itself): triangulate it when exporting"},
      // A bow tie: its two halves turn opposite ways and enclose no area together.
      {"v 0 0 0\nv 1 1 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 4\n", "line 5: polygon of 4 vertices is not convex"},
      {"", "no faces (no \"f\" statement)"},
      {"# only a comment\n\n", "no faces (no \"f\" statement)"},
      {kTriangle, "no faces (no \"f\" statement)"},
      {"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 3 2 1\n", "all 2 faces have zero area"},
      // Binary bytes are escaped, long tokens cut.
      {std::string("\x01\x7f\xff junk\n", 9), "line 1: unknown statement \"\\x01\\x7f\\xff\""},
      {std::string(40, 'w') + "\n", "line 1: unknown statement \"wwwwwwwwwwwwwwwwwwwwwwww...\""},
  };
  for (const auto& [text, expected] : bad) {
    const std::string message = obj_error(text);
    EXPECT_EQ(message.rfind(expected, 0), 0u) << "text: " << text << "\n  message:  " << message
                                              << "\n  expected: " << expected;
  }
}

TEST(ObjFile, LoadNamesWhyAFileCannotBeRead) {
  const auto load_error = [](const fs::path& file) -> std::string {
    try {
      load_obj(file);
    } catch (const ObjError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(load_error(kSourceDir / "tests/data/meshes/no_such.obj"), "no such file");
  EXPECT_EQ(load_error(kSourceDir / "tests/data/meshes"), "is a directory, not an OBJ file");
  EXPECT_EQ(load_obj(kSourceDir / "tests/data/meshes/square.obj").triangles.size(), 2u);
}

}  // namespace
}  // namespace purkinje
