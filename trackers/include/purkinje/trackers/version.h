#pragma once
namespace purkinje::trackers {
// The trackers component: detectors (glints.h), image views (image.h).
const char* component_name();
}  // namespace purkinje::trackers
