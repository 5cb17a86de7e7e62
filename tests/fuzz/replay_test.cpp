// Every fuzz target's corpus (tests/fuzz/corpus/<target>/), replayed through
// the target as an ordinary test: the seeds and every reproducer of a bug
// found so far are checked in every build, with or without clang and
// libFuzzer. A crash, a sanitizer report, an invariant the target checks
// (abort) or an exception the reader does not document fails the test.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int purkinje_fuzz_scene(const std::uint8_t* data, std::size_t size);
extern "C" int purkinje_fuzz_obj(const std::uint8_t* data, std::size_t size);
extern "C" int purkinje_fuzz_labels(const std::uint8_t* data, std::size_t size);
extern "C" int purkinje_fuzz_detections(const std::uint8_t* data, std::size_t size);
extern "C" int purkinje_fuzz_dataset_spec(const std::uint8_t* data, std::size_t size);

namespace {

using Target = int (*)(const std::uint8_t*, std::size_t);

std::vector<std::filesystem::path> corpus_files(const std::string& target) {
  const std::filesystem::path dir = std::filesystem::path(PURKINJE_FUZZ_CORPUS_DIR) / target;
  std::vector<std::filesystem::path> files;
  if (!std::filesystem::is_directory(dir)) return files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());  // a stable order, for the log
  return files;
}

void replay(const std::string& target_name, Target target) {
  const auto files = corpus_files(target_name);
  // An empty or missing corpus would pass without checking anything.
  ASSERT_FALSE(files.empty()) << "no corpus files in " << PURKINJE_FUZZ_CORPUS_DIR << "/" << target_name;
  for (const auto& file : files) {
    // Logged before the call: a crash ends the process before any test
    // message, and the last line names the input that caused it.
    std::cout << "replaying " << file.filename().string() << std::endl;
    std::ifstream in(file, std::ios::binary);
    ASSERT_TRUE(in) << "cannot open " << file;
    // A buffer of exactly the file's size, as libFuzzer passes it, so that
    // ASan sees a read past the end.
    const std::vector<std::uint8_t> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    SCOPED_TRACE(file.string());
    EXPECT_EQ(target(data.data(), data.size()), 0);
  }
}

TEST(FuzzCorpus, SceneReader) { replay("scene", purkinje_fuzz_scene); }
TEST(FuzzCorpus, ObjReader) { replay("obj", purkinje_fuzz_obj); }
TEST(FuzzCorpus, LabelsReader) { replay("labels", purkinje_fuzz_labels); }
TEST(FuzzCorpus, DetectionsReader) { replay("detections", purkinje_fuzz_detections); }
TEST(FuzzCorpus, DatasetSpecReader) { replay("dataset_spec", purkinje_fuzz_dataset_spec); }

}  // namespace
