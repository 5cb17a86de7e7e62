#include "purkinje/models/version.h"

#ifndef PURKINJE_VERSION
#error "PURKINJE_VERSION is set by models/CMakeLists.txt"
#endif

namespace purkinje {

const char* version() { return PURKINJE_VERSION; }

}  // namespace purkinje
