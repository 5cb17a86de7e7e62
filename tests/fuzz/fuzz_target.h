#pragma once
// The entry point of one fuzz target (tests/fuzz/*_fuzz.cpp), and the check
// its invariants use. Each target is built twice: alone as a libFuzzer
// program (PURKINJE_FUZZ, clang), where its entry point must be called
// LLVMFuzzerTestOneInput, and together with the others into the corpus
// replay test (every build), where the five need distinct names.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#ifdef PURKINJE_FUZZ_REPLAY
#define PURKINJE_FUZZ_TARGET(name) \
  extern "C" int purkinje_fuzz_##name(const std::uint8_t* data, std::size_t size)
#else
#define PURKINJE_FUZZ_TARGET(name) \
  extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
#endif

// A reader that returns must return what its header promises; when it does
// not, the input is a finding like a crash: abort() makes libFuzzer keep it
// and fails the replay test (the message names the broken promise).
#define PURKINJE_FUZZ_CHECK(condition)                                                            \
  do {                                                                                            \
    if (!(condition)) {                                                                           \
      std::fprintf(stderr, "%s:%d: fuzz invariant broken: %s\n", __FILE__, __LINE__, #condition); \
      std::abort();                                                                               \
    }                                                                                             \
  } while (false)

// What mesh.h promises of a mesh read (an OBJ file, or a scene's mesh once
// placed): triangles, finite vertices, indices in range, no zero area
// (the renderer takes each triangle's plane).
template <class Mesh>
void check_mesh_promises(const Mesh& mesh) {
  PURKINJE_FUZZ_CHECK(!mesh.triangles.empty());
  for (const auto& p : mesh.vertices) PURKINJE_FUZZ_CHECK(p.is_finite());
  for (const auto& t : mesh.triangles) {
    for (const std::uint32_t index : t) PURKINJE_FUZZ_CHECK(index < mesh.vertices.size());
    const auto& a = mesh.vertices[t[0]];
    PURKINJE_FUZZ_CHECK(cross(mesh.vertices[t[1]] - a, mesh.vertices[t[2]] - a).norm() > 0);
  }
}
