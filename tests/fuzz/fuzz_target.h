#pragma once
// The entry point of one fuzz target (tests/fuzz/*_fuzz.cpp), and the check
// its invariants use. Each target is built twice: alone as a libFuzzer
// program (PURKINJE_FUZZ, clang), where its entry point must be called
// LLVMFuzzerTestOneInput, and together with the others into the corpus
// replay test (every build), where the five need distinct names.

#include <sys/stat.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

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

// A folder of files a reader's input may name (a scene's meshes, a spec's
// scene) and a FIFO, made in the temporary directory so that a relative
// name never reaches a file of the tree or of the user; removed at a
// normal exit (a crash leaves it behind).
class FuzzFolder {
 public:
  FuzzFolder(const std::string& target, const std::vector<std::pair<std::string, std::string>>& files,
             const std::string& fifo) {
    std::string pattern = (std::filesystem::temp_directory_path() / ("purkinje-" + target + "-fuzz-XXXXXX")).string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      std::perror((target + " fuzz target: mkdtemp").c_str());
      std::abort();
    }
    path_ = pattern;
    for (const auto& [name, contents] : files) std::ofstream(path_ / name) << contents;
    if (::mkfifo((path_ / fifo).c_str(), 0600) != 0) {
      std::perror((target + " fuzz target: mkfifo").c_str());
      std::abort();
    }
  }
  ~FuzzFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  FuzzFolder(const FuzzFolder&) = delete;
  FuzzFolder& operator=(const FuzzFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};
