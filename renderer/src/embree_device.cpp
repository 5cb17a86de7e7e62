// The Embree device configuration, read from PURKINJE_EMBREE_CONFIG and
// checked before Embree sees it: Embree 3 ignores keys it does not know
// and quietly runs an unknown `isa` as SSE2, so a typo would go unnoticed
// (measured: "isa=bogus" gives SSE2 kernels, "frobnicate=3" is accepted).

#include <algorithm>
#include <array>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

#include "purkinje/renderer/ray_tracer.h"

namespace purkinje::renderer {

namespace {

// The instruction sets Debian's Embree 3 has kernels for, in order.
constexpr std::array<std::string_view, 5> kIsas = {"sse2", "sse4.2", "avx", "avx2", "avx512"};

// Embree 3's documented device configuration keys (rtcNewDevice).
constexpr std::array<std::string_view, 10> kKeys = {
    "threads",  "user_threads", "set_affinity",      "start_threads", "isa",
    "max_isa",  "hugepages",    "enable_selockmemoryprivilege", "verbose", "frequency_level"};

int isa_rank(std::string_view isa) {
  const auto* at = std::find(kIsas.begin(), kIsas.end(), isa);
  return at == kIsas.end() ? -1 : static_cast<int>(at - kIsas.begin());
}

std::string list(auto const& items) {
  std::string out;
  for (std::string_view item : items) out += (out.empty() ? "" : ", ") + std::string(item);
  return out;
}

// 'text', built by appending: g++ 12 at -O3 warns falsely (-Wrestrict,
// its bug 105329) on "'" + std::string(...).
std::string quoted(std::string_view text) {
  std::string out;
  out.reserve(text.size() + 2);
  out += '\'';
  out += text;
  out += '\'';
  return out;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

}  // namespace

std::string cpu_isa() {
#if defined(__x86_64__) || defined(__i386__)
  // What each of Embree's targets needs of the CPU (Embree's isa.h).
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512bw") &&
      __builtin_cpu_supports("avx512vl")) {
    return "avx512";
  }
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi") &&
      __builtin_cpu_supports("bmi2")) {
    return "avx2";
  }
  if (__builtin_cpu_supports("avx")) return "avx";
  if (__builtin_cpu_supports("sse4.2") && __builtin_cpu_supports("popcnt")) return "sse4.2";
#endif
  return "sse2";
}

EmbreeDevice embree_device(std::string_view config, std::string_view cpu) {
  const auto fail = [&](const std::string& rule) -> void {
    throw std::invalid_argument(std::string(kEmbreeConfigVariable) + "=\"" + std::string(config) + "\": " + rule);
  };
  if (isa_rank(cpu) < 0) fail("unknown CPU instruction set " + quoted(cpu));
  EmbreeDevice device;
  device.config = std::string(trim(config));
  device.isa = std::string(cpu);
  int ceiling = isa_rank(cpu);
  std::string_view rest = config;
  while (!trim(rest).empty()) {
    const std::size_t comma = rest.find(',');
    const std::string_view item = trim(rest.substr(0, comma));
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
    const std::size_t equals = item.find('=');
    if (equals == std::string_view::npos) {
      fail(quoted(item) + " is not key=value (Embree's syntax: key=value pairs separated by commas)");
    }
    const std::string_view key = trim(item.substr(0, equals));
    const std::string_view value = trim(item.substr(equals + 1));
    if (std::find(kKeys.begin(), kKeys.end(), key) == kKeys.end()) {
      fail("unknown key " + quoted(key) + " (Embree's keys: " + list(kKeys) + ")");
    }
    if (key != "isa" && key != "max_isa") continue;
    const int rank = isa_rank(value);
    if (rank < 0) fail(std::string(key) + " " + quoted(value) + " is not one of " + list(kIsas));
    if (rank > isa_rank(cpu)) {
      fail(std::string(key) + " " + std::string(value) + " needs a CPU with it; this one supports up to " +
           std::string(cpu));
    }
    if (key == "isa") device.isa = std::string(value);
    ceiling = std::min(ceiling, rank);
  }
  if (isa_rank(device.isa) > ceiling) device.isa = std::string(kIsas[static_cast<std::size_t>(ceiling)]);
  return device;
}

EmbreeDevice embree_device() {
  const char* config = std::getenv(kEmbreeConfigVariable);
  return embree_device(config ? config : "", cpu_isa());
}

}  // namespace purkinje::renderer
