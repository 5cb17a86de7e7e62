#include "cli.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <iostream>

#include "purkinje/models/output_file.h"
#include "purkinje/studies/render_set.h"

namespace purkinje::tools {

const char* const kExitCodes =
    "Exit codes:\n"
    "  0  success\n"
    "  1  bad input: a scene, labels, image or detections file is missing, malformed or invalid\n"
    "     (message on stderr)\n"
    "  2  usage error: unknown option, missing or invalid argument\n"
    "  3  output error: the output could not be written (no partial file is left)";

const CLI::Validator kFinite(
    [](const std::string& text) -> std::string {
      double value = 0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
        return "must be a finite number, not \"" + text + "\"";
      }
      return {};
    },
    "FINITE");

const CLI::Validator kSeed(
    [](const std::string& text) -> std::string {
      std::uint64_t value = 0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (text.empty() || error != std::errc() || end != text.data() + text.size()) {
        return "must be an integer from 0 to 18446744073709551615 (2^64 - 1), not \"" + text + "\"";
      }
      return {};
    },
    "SEED");

void refuse(const std::optional<Refusal>& refusal) {
  if (refusal) {
    throw CommandError(refusal->kind == Refusal::Kind::input ? kUsageError : kOutputError, refusal->message);
  }
}

void writing(const std::function<void()>& write) {
  try {
    write();
  } catch (const OutputError&) {
    throw;
  } catch (const std::exception& error) {
    throw OutputError(error.what());
  }
}

int run_command(const std::string& name, const std::function<int()>& body) {
  const auto fail = [&](const std::exception& error, int code) {
    std::cerr << "purkinje " << name << ": error: " << error.what() << "\n";
    return code;
  };
  try {
    return body();
  } catch (const CommandError& error) {
    return fail(error, error.exit_code());
  } catch (const studies::ResumeRefused& error) {
    return fail(error, kUsageError);
  } catch (const OutputError& error) {
    return fail(error, kOutputError);
  } catch (const std::exception& error) {
    return fail(error, kBadInput);
  }
}

}  // namespace purkinje::tools
