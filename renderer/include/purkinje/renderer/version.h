#pragma once
namespace purkinje::renderer {
// The renderer component; images arrive with the renderer issue.
const char* component_name();
}  // namespace purkinje::renderer
