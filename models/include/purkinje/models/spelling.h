#pragma once
// Misspellings: a key of a scene file, a subcommand or an option typed
// wrong gets "did you mean ..." instead of only "unknown".

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace purkinje {

// Whether `typed` could be a misspelling of `wanted`: a prefix of it
// ("radius" for "radius_mm") or at most two edits away (Levenshtein).
bool looks_like(std::string_view typed, std::string_view wanted);

// The candidate `typed` most likely meant (fewest edits, among those it
// looks_like), if any.
std::optional<std::string> closest_match(std::string_view typed, const std::vector<std::string>& candidates);

}  // namespace purkinje
