#pragma once
namespace purkinje::trackers {
// The trackers component; detectors arrive with the trackers issue.
const char* component_name();
}  // namespace purkinje::trackers
