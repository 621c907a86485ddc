#pragma once
/// The local (dual) frictional problem of a frictional snapshot (solvers/core/qp.hpp, Friction): with
/// contact i's rows H_i = (J_i; T_2i; T_2i+1) (FCLIB's local frame, normal first) and offsets
/// c_H,i = (c_i, cT_2i, cT_2i+1), the primal x = A^-1 (b + H'r) gives u = H x - c_H = W r + q,
///     W = H A^-1 H',   q = H A^-1 b - c_H,
/// the FrictionLocal (solvers/core/friction_problem.hpp) that the dual frictional solvers take
/// (mprgp-tresca-fp, nsgs). Formed by DualLcp (solvers/linalg/dual_lcp.hpp: CHOLMOD, dense W), so the
/// sizes are those of a dense 3m x 3m W.
#include "solvers/core/friction_problem.hpp"
#include "solvers/core/qp.hpp"
#include "solvers/linalg/dual_lcp.hpp"

#include <string>

namespace cb {

class FrictionDual {
public:
    /// Forms W and q (qp's arrays must outlive this object). Throws InputError naming `name` when the snapshot has no
    /// friction, or when CHOLMOD cannot factor A.
    FrictionDual(const QpView& qp, const std::string& name);

    const FrictionLocal& local() const { return m_local; }
    /// x = A^-1 (b + H'r), r in the local frame (3 per contact).
    Vec primal(const Vec& r);
    const Counters& counters() const { return m_counters; }

private:
    const QpView m_qp;  // a copy: its references are the snapshot's arrays, which outlive it
    SpMat m_H;
    Vec m_cH;
    DualLcp m_dual;
    FrictionLocal m_local;
    Counters m_counters;
};

}  // namespace cb
