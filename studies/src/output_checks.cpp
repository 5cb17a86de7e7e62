#include "purkinje/studies/output_checks.h"

#include "purkinje/models/labels.h"
#include "purkinje/models/output_file.h"

namespace purkinje::studies {

namespace fs = std::filesystem;

void remove_stale_outputs(const fs::path& folder, const std::vector<std::string>& files) {
  for (const std::string& name : files) {
    std::error_code ec;
    fs::remove(folder / name, ec);  // false without error when it does not exist
    if (ec) throw OutputError((folder / name).string() + ": the last run's file cannot be removed: " + ec.message());
  }
}

bool same_file(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  return fs::equivalent(a, b, ec) && !ec;
}

std::optional<Refusal> check_output_file(const fs::path& file, const std::vector<fs::path>& inputs) {
  for (const fs::path& input : inputs) {
    if (same_file(file, input)) {
      return Refusal{Refusal::Kind::input, "-o " + file.string() + ": is an input of this command (" + input.string() +
                                      "): not overwritten"};
    }
  }
  if (const std::string why = unreplaceable(file); !why.empty()) {
    return Refusal{Refusal::Kind::output, "-o " + file.string() + ": " + why};
  }
  return std::nullopt;
}

std::optional<Refusal> check_output_folder(const fs::path& folder, const std::vector<fs::path>& input_folders,
                                           const std::vector<std::string>& files,
                                           const std::vector<fs::path>& inputs) {
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(folder, ec);
  if (fs::exists(status) && !fs::is_directory(fs::status(folder, ec))) {
    return Refusal{Refusal::Kind::output, "-o " + folder.string() + ": exists and is not a folder: not replaced"};
  }
  for (const fs::path& input : input_folders) {
    if (same_file(folder, input)) {
      return Refusal{Refusal::Kind::input, "-o " + folder.string() + ": is an input folder of this command (" +
                                      input.string() + "); write the output to another folder"};
    }
  }
  for (const std::string& name : files) {
    if (const auto refusal = check_output_file(folder / name, inputs)) return refusal;
  }
  return std::nullopt;
}

}  // namespace purkinje::studies
