// Input files are read whole only when they are regular files of a sane
// size: a FIFO would block forever, /dev/zero would fill the memory.

#include "purkinje/models/input_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "purkinje/models/labels.h"
#include "purkinje/models/obj_file.h"
#include "purkinje/models/scene_file.h"

namespace purkinje {
namespace {

class InputFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("purkinje_input_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::filesystem::path write(const std::string& name, const std::string& text) const {
    const auto path = dir_ / name;
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  // The reason read_input_file gives, or "" when it reads the file.
  static std::string refusal(const std::filesystem::path& file, std::uintmax_t max_bytes) {
    try {
      read_input_file(file, max_bytes, "a test file");
    } catch (const InputFileError& e) {
      EXPECT_EQ(std::string(e.what()), file.string() + ": " + e.reason());
      EXPECT_EQ(unreadable_input(file, max_bytes, "a test file"), e.reason()) << "the two checks differ";
      return e.reason();
    }
    return "";
  }

  std::filesystem::path dir_;
};

TEST_F(InputFile, ReadsARegularFileWhole) {
  const std::string text(100000, 'x');
  EXPECT_EQ(read_input_file(write("a.txt", text), 100000, "a test file"), text);
  EXPECT_EQ(read_input_file(write("empty.txt", ""), 10, "a test file"), "");
  EXPECT_EQ(unreadable_input(dir_ / "a.txt", 100000, "a test file"), "");
}

TEST_F(InputFile, RefusesWhatIsNotARegularFileWithoutReadingIt) {
  EXPECT_EQ(refusal(dir_ / "missing.json", 100), "no such file");
  EXPECT_EQ(refusal(dir_, 100), "is a directory, not a test file");
  EXPECT_EQ(refusal("/dev/zero", 100), "is a character device, not a test file");
  EXPECT_EQ(refusal("/dev/null", 100), "is a character device, not a test file");
  // A FIFO with no writer: open() would block without O_NONBLOCK.
  const auto fifo = dir_ / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(refusal(fifo, 100), "is a FIFO (named pipe), not a test file");
}

TEST_F(InputFile, RefusesFilesOverTheLimitByTheirSizeOrWhatTheyHold) {
  EXPECT_EQ(refusal(write("big.txt", std::string(3u << 20, 'x')), 1u << 20),
            "is 3 MB, more than the 1 MB a test file may have");
  EXPECT_EQ(refusal(write("edge.txt", std::string(1001, 'x')), 1000),
            "is 1001 bytes, more than the 1000 bytes a test file may have");
  // Files in /proc report a size of 0 but hold more: the read stops there.
  EXPECT_EQ(unreadable_input("/proc/self/maps", 10, "a test file"), "") << "no size to tell by";
  try {
    read_input_file("/proc/self/maps", 10, "a test file");
    ADD_FAILURE() << "accepted";
  } catch (const InputFileError& e) {
    EXPECT_EQ(e.reason(), "holds more than the 10 bytes a test file may have");
  }
}

TEST_F(InputFile, EveryReaderRefusesADeviceNamingTheFile) {
  const auto message = [](auto read) {
    try {
      read();
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message([] { load_scene("/dev/zero"); }),
            "/dev/zero: cannot read: is a character device, not a scene file");
  EXPECT_EQ(message([] { load_obj("/dev/urandom"); }), "is a character device, not an OBJ file");
  EXPECT_EQ(message([] { read_image_labels("/dev/zero"); }), "/dev/zero: is a character device, not a labels file");
}

// nlohmann::json throws out_of_range, not parse_error, for a number beyond
// double's range: it once escaped the labels reader.
TEST_F(InputFile, LabelsWithANumberBeyondDoublesRangeAreNotJson) {
  const auto file = write("big_number.json", R"({"labels_format": 1e400})");
  try {
    read_image_labels(file);
    ADD_FAILURE() << "accepted";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(file.string() + ": not JSON: ", 0), 0u) << what;
    EXPECT_NE(what.find("1e400"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace purkinje

namespace purkinje {
namespace {

// The CRC-32 labels record is zlib's (ISO-HDLC): the standard check value
// of "123456789" is 0xcbf43926.
TEST(FileCheck, IsTheStandardCrc32WithTheSize) {
  const FileCheck check = file_check_of("123456789");
  EXPECT_EQ(check.bytes, 9u);
  EXPECT_EQ(check.crc32, 0xcbf43926u);
  EXPECT_EQ(crc32_text(check.crc32), "cbf43926");
  EXPECT_EQ(crc32_text(0x1a), "0000001a");
  EXPECT_EQ(file_check_of("").crc32, 0u);
}

TEST(FileCheck, OfAFileReadInPiecesEqualsOfItsContents) {
  const auto file = std::filesystem::temp_directory_path() / ("purkinje_check_" + std::to_string(::getpid()));
  std::string text;
  for (int i = 0; i < 200000; ++i) text += static_cast<char>('a' + i % 26);
  std::ofstream(file, std::ios::binary) << text;
  EXPECT_EQ(file_check_of_file(file), file_check_of(text));
  std::filesystem::remove(file);
  EXPECT_THROW(file_check_of_file(file), InputFileError);
  EXPECT_THROW(file_check_of_file("/dev/zero"), InputFileError);
}

}  // namespace
}  // namespace purkinje
