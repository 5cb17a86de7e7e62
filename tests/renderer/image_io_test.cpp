#include "purkinje/renderer/image_io.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace purkinje::renderer {
namespace {

namespace fs = std::filesystem;

// A fresh directory per test, removed with everything in it at the end.
class ScratchDirectory {
 public:
  ScratchDirectory() {
    static std::atomic<int> counter{0};
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "purkinje-image-io-";
    name += test ? test->name() : "test";
    name += '-';
    name += std::to_string(::getpid());
    name += '-';
    name += std::to_string(counter++);
    path_ = fs::temp_directory_path() / name;
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDirectory() {
    std::error_code ignored;
    fs::permissions(path_, fs::perms::owner_all, fs::perm_options::add, ignored);
    fs::remove_all(path_, ignored);
  }
  ScratchDirectory(const ScratchDirectory&) = delete;
  ScratchDirectory& operator=(const ScratchDirectory&) = delete;

  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

  // Every entry, hidden ones included, sorted.
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(path_)) names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  }

 private:
  fs::path path_;
};

std::vector<unsigned char> bytes_of(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_text(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
  if (!out.flush()) throw std::runtime_error(file.string() + ": cannot write");
}

std::string text_of(const fs::path& file) {
  const auto bytes = bytes_of(file);
  return std::string(bytes.begin(), bytes.end());
}

SensorImage sensor_image(int width, int height, int bits, std::vector<unsigned short> values) {
  SensorImage image;
  image.width = width;
  image.height = height;
  image.bits = bits;
  image.values = std::move(values);
  return image;
}

NamedPlane named_plane(const std::string& name, int width, int height, std::vector<float> values) {
  NamedPlane p;
  p.name = name;
  p.plane.width = width;
  p.plane.height = height;
  p.plane.values = std::move(values);
  return p;
}

// Deterministic, poorly compressible floats (a 32-bit LCG), so an EXR of
// them stays large after zip compression.
std::vector<float> noise(std::size_t count, std::uint32_t seed) {
  std::vector<float> values(count);
  for (float& v : values) {
    seed = seed * 1664525u + 1013904223u;
    v = static_cast<float>(seed >> 8) / 16777216.0f;
  }
  return values;
}

std::string message_of_output_error(FileSet& set) {
  try {
    set.commit();
  } catch (const OutputError& e) {
    return e.what();
  }
  return "(no OutputError)";
}

bool starts_with(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

// --- PNG and EXR files, read independently of OpenImageIO -----------------

std::uint32_t big_endian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

// Chunk types of a PNG file, in order (PNG spec: 8-byte signature, then
// length, type, data, CRC).
std::vector<std::string> png_chunks(const std::vector<unsigned char>& png) {
  std::vector<std::string> chunks;
  std::size_t at = 8;
  while (at + 12 <= png.size()) {
    const std::uint32_t length = big_endian32(&png[at]);
    chunks.emplace_back(reinterpret_cast<const char*>(&png[at + 4]), 4);
    at += 12 + length;
  }
  return chunks;
}

// Attribute names and raw values of a single-part EXR header (OpenEXR
// file layout: magic, version, then name\0 type\0 size value ... \0).
std::map<std::string, std::vector<unsigned char>> exr_header(
    const std::vector<unsigned char>& exr) {
  std::map<std::string, std::vector<unsigned char>> attributes;
  std::size_t at = 8;
  auto read_string = [&] {
    std::string s;
    while (at < exr.size() && exr[at] != 0) s += static_cast<char>(exr[at++]);
    ++at;
    return s;
  };
  while (at < exr.size() && exr[at] != 0) {
    const std::string name = read_string();
    read_string();  // type
    const std::uint32_t size = std::uint32_t{exr[at]} | (std::uint32_t{exr[at + 1]} << 8) |
                               (std::uint32_t{exr[at + 2]} << 16) |
                               (std::uint32_t{exr[at + 3]} << 24);
    at += 4;
    attributes[name].assign(exr.begin() + static_cast<std::ptrdiff_t>(at),
                            exr.begin() + static_cast<std::ptrdiff_t>(at + size));
    at += size;
  }
  return attributes;
}

// ---------------------------------------------------------------------------

TEST(Png, RoundTrips8BitValuesUnchanged) {
  ScratchDirectory dir;
  const auto image = sensor_image(3, 2, 8, {0, 1, 127, 128, 254, 255});
  write_png(dir / "a.png", image);
  const SensorImage back = read_png(dir / "a.png");
  EXPECT_EQ(back.width, 3);
  EXPECT_EQ(back.height, 2);
  EXPECT_EQ(back.bits, 8);
  EXPECT_EQ(back.values, image.values);
}

TEST(Png, Stores12BitValuesInTheTopBitsOf16) {
  ScratchDirectory dir;
  write_png(dir / "a.png", sensor_image(2, 2, 12, {0, 1, 2048, 4095}));
  const SensorImage back = read_png(dir / "a.png");
  EXPECT_EQ(back.bits, 16);
  // 1 << 4 = 16, 2048 << 4 = 32768, 4095 << 4 = 65520.
  EXPECT_EQ(back.values, (std::vector<unsigned short>{0, 16, 32768, 65520}));
  for (std::size_t i = 0; i < back.values.size(); ++i)
    EXPECT_EQ(back.values[i] >> 4, (std::vector<int>{0, 1, 2048, 4095})[i]);
}

TEST(Png, Stores10And16BitValues) {
  ScratchDirectory dir;
  write_png(dir / "ten.png", sensor_image(3, 1, 10, {1, 512, 1023}));
  EXPECT_EQ(read_png(dir / "ten.png").values, (std::vector<unsigned short>{64, 32768, 65472}));
  write_png(dir / "sixteen.png", sensor_image(1, 3, 16, {0, 1234, 65535}));
  const SensorImage back = read_png(dir / "sixteen.png");
  EXPECT_EQ(back.width, 1);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.bits, 16);
  EXPECT_EQ(back.values, (std::vector<unsigned short>{0, 1234, 65535}));
}

TEST(Png, RejectsInvalidImagesWithoutCreatingAFile) {
  ScratchDirectory dir;
  auto rejects = [&](const SensorImage& image, const std::string& fragment) {
    try {
      write_png(dir / "bad.png", image);
      ADD_FAILURE() << "accepted, expected: " << fragment;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "bad.png"));
  };
  rejects(sensor_image(2, 1, 9, {0, 0}), "bits = 9");
  rejects(sensor_image(2, 1, 12, {4095, 4096}), "value 4096 at pixel (1, 0)");
  rejects(sensor_image(2, 1, 8, {256, 0}), "value 256 at pixel (0, 0)");
  rejects(sensor_image(2, 2, 8, {0, 0, 0}), "3 values for 2 x 2");
  rejects(sensor_image(0, 1, 8, {}), "size 0 x 1");
}

TEST(Png, ReadingAMissingOrForeignFileNamesIt) {
  ScratchDirectory dir;
  const fs::path missing = dir / "missing.png";
  try {
    read_png(missing);
    ADD_FAILURE() << "read a missing file";
  } catch (const OutputError& e) {
    EXPECT_TRUE(starts_with(e.what(), missing.string() + ": ")) << e.what();
  }
  const fs::path text = dir / "text.png";
  write_text(text, "not an image at all");
  EXPECT_THROW(read_png(text), OutputError);
  // An EXR is a readable image, but not a single-channel PNG.
  write_exr(dir / "a.exr", {named_plane("R", 1, 1, {1.0f})});
  EXPECT_THROW(read_png(dir / "a.exr"), OutputError);
}

TEST(Exr, RoundTripsChannelNamesAndValues) {
  ScratchDirectory dir;
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<NamedPlane> planes = {
      named_plane("R", 2, 2, {0.0f, 0.25f, 1.0f, 1e-30f}),
      named_plane("depth", 2, 2, {612.5f, 600.0f, inf, 599.875f}),
      named_plane("N.x", 2, 2, {-1.0f, 0.5f, -0.0f, 0.70710677f}),
      named_plane("id", 2, 2, {0.0f, 1.0f, 2.0f, 16777216.0f}),
      named_plane("glint.led0", 2, 2, {3.5e6f, 0.0f, 1e-6f, 123.456f}),
  };
  write_exr(dir / "aov.exr", planes);
  const std::vector<NamedPlane> back = read_exr(dir / "aov.exr");
  ASSERT_EQ(back.size(), planes.size());
  std::map<std::string, const ImagePlane*> by_name;
  for (const NamedPlane& p : back) by_name[p.name] = &p.plane;
  for (const NamedPlane& p : planes) {
    ASSERT_EQ(by_name.count(p.name), 1u) << p.name;
    const ImagePlane& b = *by_name[p.name];
    EXPECT_EQ(b.width, 2);
    EXPECT_EQ(b.height, 2);
    // 32-bit float storage: bit-exact.
    EXPECT_EQ(b.values, p.plane.values) << p.name;
  }
  // The sign of -0 survives too (float comparison above cannot tell).
  EXPECT_TRUE(std::signbit(by_name["N.x"]->at(0, 1)));
}

TEST(Exr, RejectsPlanesThatDoNotFormOneImage) {
  ScratchDirectory dir;
  const fs::path file = dir / "bad.exr";
  auto rejects = [&](const std::vector<NamedPlane>& planes, const std::string& fragment) {
    try {
      write_exr(file, planes);
      ADD_FAILURE() << "accepted, expected: " << fragment;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(file));
  };
  rejects({}, "no planes");
  rejects({named_plane("R", 2, 1, {0, 0}), named_plane("depth", 1, 2, {0, 0})},
          "\"depth\" is 1 x 2, the first plane \"R\" is 2 x 1");
  rejects({named_plane("R", 2, 1, {0, 0}), named_plane("R", 2, 1, {0, 0})}, "appears twice");
  rejects({named_plane("", 1, 1, {0})}, "empty name");
  rejects({named_plane("R", 2, 1, {0})}, "has 1 values for 2 pixels");
  rejects({named_plane("depth", 2, 1, {1.0f, std::nanf("")})}, "NaN at pixel (1, 0)");
}

TEST(ImageFiles, EqualInputsGiveEqualBytesWithoutDates) {
  ScratchDirectory dir;
  const auto image = sensor_image(4, 3, 12, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 4094, 4095});
  const std::vector<NamedPlane> planes = {named_plane("depth", 4, 3, noise(12, 1)),
                                          named_plane("R", 4, 3, noise(12, 2))};
  write_png(dir / "first.png", image);
  write_exr(dir / "first.exr", planes);
  // OIIO's default date has one-second resolution: cross a second boundary
  // so a stamped time would differ.
  const auto now = std::chrono::system_clock::now();
  std::this_thread::sleep_until(std::chrono::ceil<std::chrono::seconds>(now) +
                                std::chrono::milliseconds(20));
  write_png(dir / "second.png", image);
  write_exr(dir / "second.exr", planes);
  EXPECT_TRUE(bytes_of(dir / "first.png") == bytes_of(dir / "second.png"));
  EXPECT_TRUE(bytes_of(dir / "first.exr") == bytes_of(dir / "second.exr"));

  // No time (tIME) and no text (tEXt, zTXt, iTXt, where software names go).
  for (const std::string& chunk : png_chunks(bytes_of(dir / "first.png")))
    EXPECT_TRUE(chunk == "IHDR" || chunk == "IDAT" || chunk == "IEND" || chunk == "oFFs")
        << "unexpected PNG chunk " << chunk;

  // Only the attributes OpenEXR requires: no capDate, owner, comments...
  const auto header = exr_header(bytes_of(dir / "first.exr"));
  std::set<std::string> names;
  for (const auto& [name, value] : header) names.insert(name);
  EXPECT_EQ(names, (std::set<std::string>{"channels", "compression", "dataWindow", "displayWindow",
                                          "lineOrder", "pixelAspectRatio", "screenWindowCenter",
                                          "screenWindowWidth"}));
  // Compression 3 is ZIP (16 scan lines per block) in the OpenEXR format.
  ASSERT_EQ(header.at("compression").size(), 1u);
  EXPECT_EQ(header.at("compression")[0], 3);
}

// --- FileSet ---------------------------------------------------------------

TEST(FileSet, CommitWritesEveryFileAndLeavesNoTemporary) {
  ScratchDirectory dir;
  write_text(dir / "image.png", "left over from an earlier run");
  const auto image = sensor_image(2, 1, 8, {7, 200});
  FileSet set;
  std::vector<fs::path> temporaries;
  set.add(dir / "image.png", [&](const fs::path& t) {
    temporaries.push_back(t);
    write_png(t, image);
  });
  set.add(dir / "aov.exr", [&](const fs::path& t) {
    temporaries.push_back(t);
    write_exr(t, {named_plane("depth", 2, 1, {1.5f, 2.5f})});
  });
  set.add(dir / "labels.json", [&](const fs::path& t) {
    temporaries.push_back(t);
    write_text(t, "{}\n");
  });
  set.commit();

  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"aov.exr", "image.png", "labels.json"}));
  EXPECT_EQ(read_png(dir / "image.png").values, image.values);
  EXPECT_EQ(read_exr(dir / "aov.exr").at(0).plane.values, (std::vector<float>{1.5f, 2.5f}));
  EXPECT_EQ(text_of(dir / "labels.json"), "{}\n");
  // Temporaries are hidden siblings named after their target.
  ASSERT_EQ(temporaries.size(), 3u);
  EXPECT_EQ(temporaries[0].parent_path(), dir.path());
  EXPECT_TRUE(
      starts_with(temporaries[0].filename(), ".image.png.tmp." + std::to_string(::getpid()) + "."))
      << temporaries[0];
}

TEST(FileSet, MissingDirectoryIsNamedAndNothingIsWritten) {
  ScratchDirectory dir;
  FileSet set;
  bool ran = false;
  set.add(dir / "fine.png", [&](const fs::path& t) {
    ran = true;
    write_text(t, "x");
  });
  set.add(dir / "missing" / "image.png", [&](const fs::path& t) { write_text(t, "x"); });
  EXPECT_EQ(message_of_output_error(set), (dir / "missing" / "image.png").string() + ": cannot write: the folder " +
                                             (dir / "missing").string() + "/ does not exist");
  EXPECT_FALSE(ran);
  EXPECT_TRUE(dir.entries().empty());
}

TEST(FileSet, ParentThatIsARegularFileFails) {
  // Works as root too, where permission bits do not stop writes.
  ScratchDirectory dir;
  write_text(dir / "plain", "a file, not a folder");
  FileSet set;
  set.add(dir / "plain" / "image.png", [](const fs::path& t) { write_text(t, "x"); });
  EXPECT_EQ(message_of_output_error(set), (dir / "plain" / "image.png").string() + ": cannot write: the folder " +
                                             (dir / "plain").string() + "/ is not a folder");
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"plain"}));
}

TEST(FileSet, ReadOnlyDirectoryFailsWithoutPartialFiles) {
  ScratchDirectory dir;
  fs::create_directory(dir / "ro");
  fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec |
                                  fs::perms::group_read | fs::perms::group_exec |
                                  fs::perms::others_read | fs::perms::others_exec);
  {
    // Root (or CAP_DAC_OVERRIDE) writes regardless of the mode bits.
    std::ofstream probe(dir / "ro" / "probe");
    if (probe) {
      probe.close();
      fs::remove(dir / "ro" / "probe");
      GTEST_SKIP() << "permission bits do not stop this user from writing";
    }
  }
  FileSet set;
  set.add(dir / "ro" / "image.png",
          [](const fs::path& t) { write_png(t, sensor_image(1, 1, 8, {1})); });
  const std::string message = message_of_output_error(set);
  EXPECT_TRUE(starts_with(message, (dir / "ro" / "image.png").string() + ": cannot write: "))
      << message;
  EXPECT_NE(message.find(std::strerror(EACCES)), std::string::npos) << message;
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir / "ro")) left.push_back(e.path().filename());
  EXPECT_TRUE(left.empty());
}

TEST(FileSet, ThrowingWriterRemovesEveryTemporaryAndKeepsOldFiles) {
  ScratchDirectory dir;
  write_text(dir / "b.json", "from an earlier run");
  FileSet set;
  std::vector<fs::path> temporaries;
  bool third_ran = false;
  set.add(dir / "a.png", [&](const fs::path& t) {
    temporaries.push_back(t);
    write_png(t, sensor_image(1, 1, 8, {1}));
  });
  set.add(dir / "b.json", [&](const fs::path& t) {
    temporaries.push_back(t);
    write_text(t, "half a fi");
    throw std::runtime_error("label writer gave up");
  });
  set.add(dir / "c.exr", [&](const fs::path&) { third_ran = true; });
  EXPECT_EQ(message_of_output_error(set), (dir / "b.json").string() + ": label writer gave up");
  EXPECT_FALSE(third_ran);
  ASSERT_EQ(temporaries.size(), 2u);
  for (const auto& t : temporaries) EXPECT_FALSE(fs::exists(t)) << t;
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"b.json"}));
  EXPECT_EQ(text_of(dir / "b.json"), "from an earlier run");
}

TEST(FileSet, InvalidImageInsideASetBecomesAnOutputErrorNamingTheTarget) {
  ScratchDirectory dir;
  FileSet set;
  set.add(dir / "a.png", [](const fs::path& t) { write_png(t, sensor_image(1, 1, 8, {300})); });
  const std::string message = message_of_output_error(set);
  EXPECT_TRUE(starts_with(message, (dir / "a.png").string() + ": write_png: value 300")) << message;
  EXPECT_TRUE(dir.entries().empty());
}

TEST(FileSet, WriterThatWritesNothingFails) {
  ScratchDirectory dir;
  FileSet set;
  set.add(dir / "a.png", [](const fs::path& t) { fs::remove(t); });
  EXPECT_EQ(message_of_output_error(set), (dir / "a.png").string() + ": the writer left no file");
  EXPECT_TRUE(dir.entries().empty());
}

TEST(FileSet, RefusesToReplaceAnythingButARegularFileBeforeWriting) {
  ScratchDirectory dir;
  fs::create_directories(dir / "b.png" / "inside");
  FileSet set;
  bool wrote = false;
  set.add(dir / "a.png", [&](const fs::path& t) {
    wrote = true;
    write_png(t, sensor_image(1, 1, 8, {1}));
  });
  set.add(dir / "b.png", [](const fs::path& t) { write_png(t, sensor_image(1, 1, 8, {2})); });
  EXPECT_EQ(message_of_output_error(set), (dir / "b.png").string() + ": is a folder: not replaced");
  EXPECT_FALSE(wrote);
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"b.png"}));
}

TEST(FileSet, FailedRenameRemovesTargetsAlreadyRenamed) {
  ScratchDirectory dir;
  // A non-empty directory appears where the second file should go after
  // the checks: rename(2) refuses to replace it, after the first file was
  // already in place.
  FileSet set;
  set.add(dir / "a.png", [](const fs::path& t) { write_png(t, sensor_image(1, 1, 8, {1})); });
  set.add(dir / "b.png", [&](const fs::path& t) {
    write_png(t, sensor_image(1, 1, 8, {2}));
    fs::create_directories(dir / "b.png" / "inside");
  });
  const std::string message = message_of_output_error(set);
  EXPECT_TRUE(starts_with(message, (dir / "b.png").string() + ": cannot rename into place: "))
      << message;
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"b.png"}));
  EXPECT_TRUE(fs::is_directory(dir / "b.png" / "inside"));
}

TEST(FileSet, RejectsTheSameTargetTwice) {
  FileSet set;
  set.add("out/a.png", [](const fs::path&) {});
  EXPECT_THROW(set.add("out/./a.png", [](const fs::path&) {}), std::invalid_argument);
  // A folder's path is no file to write: an output error, as the command
  // line reports it (exit 3), naming the path.
  EXPECT_THROW(set.add("out/", [](const fs::path&) {}), OutputError);
  EXPECT_THROW(set.add("out/b.png", FileSet::Writer()), std::invalid_argument);
}

// Full disk, simulated by a file-size limit: writes past it fail with
// EFBIG (SIGXFSZ ignored). The limit must apply to a process of its own,
// and that process must be a fresh one (fork, then exec this test binary):
// after OpenEXR has started its thread pool, a forked copy that writes an
// EXR waits forever for pool threads that fork did not copy.
constexpr const char* kFullDiskVariable = "PURKINJE_IMAGE_IO_FULL_DISK_DIR";
constexpr rlim_t kFileSizeLimit = 4096;

enum ChildResult : int {
  kRightError = 0,
  kNoError = 10,
  kWrongMessage = 11,
  kOtherException = 12,
  kLimitMissing = 13,
};

[[noreturn]] void run_full_disk_child(const fs::path& dir) {
  int result = kRightError;
  rlimit limit{};
  if (::getrlimit(RLIMIT_FSIZE, &limit) != 0 || limit.rlim_cur != kFileSizeLimit) {
    result = kLimitMissing;
  } else {
    try {
      FileSet set;
      set.add(dir / "small.png", [](const fs::path& t) {
        write_png(t, sensor_image(4, 4, 8, std::vector<unsigned short>(16, 9)));
      });
      // About 512 kB of noise, far beyond the limit even compressed.
      set.add(dir / "big.exr", [](const fs::path& t) {
        write_exr(t, {named_plane("R", 256, 256, noise(65536, 3)),
                      named_plane("depth", 256, 256, noise(65536, 4))});
      });
      set.commit();
      result = kNoError;
    } catch (const OutputError& e) {
      const std::string message = e.what();
      const bool names_target =
          starts_with(message, (dir / "big.exr").string() + ": cannot write: ");
      const bool gives_reason = message.find(std::strerror(EFBIG)) != std::string::npos;
      result = names_target && gives_reason ? kRightError : kWrongMessage;
    } catch (...) {
      result = kOtherException;
    }
  }
  std::fflush(nullptr);
  ::_exit(result);
}

TEST(FileSet, FullDiskLeavesNoFile) {
  if (const char* child_dir = std::getenv(kFullDiskVariable)) run_full_disk_child(child_dir);

  ScratchDirectory dir;
  // Everything the child needs is built before fork: between fork and exec
  // only async-signal-safe calls are allowed.
  std::vector<std::string> environment;
  for (char** e = environ; *e != nullptr; ++e) {
    // GTEST_* (sharding, output files) could skip the test or write files.
    if (starts_with(*e, "GTEST_") || starts_with(*e, kFullDiskVariable)) continue;
    environment.emplace_back(*e);
  }
  environment.push_back(std::string(kFullDiskVariable) + "=" + dir.path().string());
  std::vector<char*> envp;
  for (std::string& e : environment) envp.push_back(e.data());
  envp.push_back(nullptr);
  std::string program = "/proc/self/exe";
  std::string filter = "--gtest_filter=FileSet.FullDiskLeavesNoFile";
  std::vector<char*> argv = {program.data(), filter.data(), nullptr};
  const rlimit limit{kFileSizeLimit, kFileSizeLimit};

  const pid_t child = ::fork();
  ASSERT_GE(child, 0) << std::strerror(errno);
  if (child == 0) {
    // Both survive exec: the ignored signal and the resource limit.
    ::signal(SIGXFSZ, SIG_IGN);
    if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(126);
    ::execve(program.c_str(), argv.data(), envp.data());
    ::_exit(127);
  }

  int status = 0;
  pid_t waited = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while ((waited = ::waitpid(child, &status, WNOHANG)) == 0 &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  if (waited == 0) {
    ::kill(child, SIGKILL);
    ::waitpid(child, &status, 0);
    FAIL() << "the child process did not finish within 60 s";
  }
  ASSERT_TRUE(WIFEXITED(status)) << "child ended by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), kRightError)
      << "0: OutputError naming big.exr and EFBIG; 10: no error; 11: wrong message; "
         "12: other exception; 13: limit not inherited; 126/127: setup or exec failed";
  EXPECT_TRUE(dir.entries().empty());
}

}  // namespace
}  // namespace purkinje::renderer
