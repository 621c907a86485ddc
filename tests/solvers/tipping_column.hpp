#pragma once
/// The stiff test body of the deflation tests (mprgp's and cg's): a column of 4 x 10 x 4 cubes,
/// E = 1e10 Pa, h = 0.05 s, dropped at 3 m/s onto a ground tilted by 30 degrees. It lands on an
/// edge and its slow tipping mode decides which few of its rows stay active; its rigid modes are
/// A's slowest ones. Without deflation mprgp + ichol needs 2.6x the iterations of cg + ichol.
#include "problems/synthetic.hpp"

namespace cb::testing_qps {

inline Qp tipping_column()
{
    return make_synthetic("plane",
                          {{"youngs", 1e10},
                           {"h", 0.05},
                           {"nx", 4},
                           {"ny", 10},
                           {"nz", 4},
                           {"tilt_deg", 30.0},
                           {"speed", 3.0},
                           {"margin", 4.0}},
                          4);
}

}  // namespace cb::testing_qps
