#pragma once
/// The largest absolute entry of a vector, 0 for an empty one.
#include "solvers/core/types.hpp"

namespace cb::test {

inline double max_abs(const Vec& v) { return v.size() ? v.cwiseAbs().maxCoeff() : 0.0; }

}  // namespace cb::test
