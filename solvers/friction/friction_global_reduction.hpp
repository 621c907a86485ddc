#pragma once
/// The local (reduced) problem of a global frictional problem (solvers/core/friction_global.hpp): from
/// M v = H r + f, v = M^-1 (H r + f), so u = H' v + w = W r + q with
///   W = H' M^-1 H,   q = w + H' M^-1 f.
/// (The plus sign: FCLIB's f stands on the right of M v = H r + f; Siconos' own reformulation,
/// globalFrictionContact_reformulation_FrictionContact, computes the same q = b + H' M^-1 q_Siconos.)
/// M is factored once by CHOLMOD and W formed sparse by Delassus (solvers/linalg/delassus.hpp); the
/// factor also gives back v for any r, so a solver of the local problem answers the global one.
#include "solvers/core/friction_global.hpp"
#include "solvers/core/friction_problem.hpp"
#include "solvers/linalg/delassus.hpp"

namespace cb {

class GlobalReduction {
public:
    /// Factors M; throws InputError("NAME: /fclib_global/M: ...") when M is not positive definite.
    explicit GlobalReduction(const FrictionGlobal& problem);

    /// The local problem (W row-major, 3m x 3m; q; mu copied; name kept).
    const FrictionLocal& local() const { return m_local; }

    /// v = M^-1 (H r + f).
    Vec velocity(const Vec& r) const;

private:
    const FrictionGlobal& m_problem;
    Delassus m_delassus;
    FrictionLocal m_local;
};

}  // namespace cb
