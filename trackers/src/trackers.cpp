#include "purkinje/trackers/version.h"
namespace purkinje::trackers {
const char* component_name() { return "trackers"; }
}  // namespace purkinje::trackers
