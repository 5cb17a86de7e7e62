#include "purkinje/renderer/version.h"
namespace purkinje::renderer {
const char* component_name() { return "renderer"; }
}  // namespace purkinje::renderer
