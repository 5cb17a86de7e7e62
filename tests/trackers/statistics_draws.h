#pragma once
// How many noisy draws the statistical checks take: the calibration
// issue's 1000 unless PURKINJE_STATISTICS_DRAWS says fewer (at 200 draws a
// standard deviation is still good to 5%).

#include "environment_count.h"

namespace purkinje::trackers {

inline int statistics_draws() { return testing::count_from_environment("PURKINJE_STATISTICS_DRAWS", 1000, 100); }

}  // namespace purkinje::trackers
