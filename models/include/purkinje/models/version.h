#pragma once

namespace purkinje {

// The project's version, as in the top-level CMakeLists.txt: what a data
// set's manifest and labels record beside their bytes.
const char* version();

}  // namespace purkinje
