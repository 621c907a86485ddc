// The list of built-in solvers: one line per solver (see README "Adding a solver").
#include "solvers/active_set.hpp"
#include "solvers/cg.hpp"
#include "solvers/ica.hpp"
#include "solvers/mprgp.hpp"
#include "solvers/mprgp_box.hpp"
#include "solvers/mprgp_coupled.hpp"
#include "solvers/pgs.hpp"
#include "solvers/registry.hpp"
#ifdef CB_HAVE_IPOPT
#include "solvers/peers/ipopt_solver.hpp"
#endif
#ifdef CB_HAVE_BULLET
#include "solvers/peers/bullet_dantzig.hpp"
#endif
#ifdef CB_HAVE_PETSC
#include "solvers/peers/tao_pdipm.hpp"
#include "solvers/peers/tao_tron.hpp"
#endif
#ifdef CB_HAVE_SICONOS
#include "solvers/peers/siconos_lemke.hpp"
#include "solvers/peers/siconos_nsn.hpp"
#endif

namespace cb {

namespace {

/// The entry with its applicability line (what `contactbench solvers` prints beside the name).
SolverEntry applies_to(SolverEntry entry, const char* problems)
{
    entry.applies_to = problems;
    return entry;
}

}  // namespace

void register_builtin_solvers(SolverRegistry& registry)
{
    // REGISTRATIONS (one line each): registry.add("name", name_entry());
    registry.add("active-set", applies_to(active_set_entry(), "any J (dense Schur complement of the working set)"));
    registry.add("cg", applies_to(cg_entry(), "ignores J (solves Ax = b)"));
    registry.add("mprgp", applies_to(mprgp_entry(), "decoupled rows only (the harness decouples a coupled J first)"));
    registry.add("mprgp-box", applies_to(mprgp_box_entry(), "bounds only (every row of J has at most one nonzero)"));
    registry.add("mprgp-coupled", applies_to(mprgp_coupled_entry(), "any J"));
    registry.add("ica", applies_to(ica_entry(), "any J"));
    registry.add("pgs", applies_to(pgs_entry(), "any J with at most max_rows rows (2000; the dual matrix is dense)"));
    // External peers (solvers/peers/), each only when CMake found its library:
#ifdef CB_HAVE_IPOPT
    registry.add("ipopt", applies_to(ipopt_entry(), "any J (interior point on the primal QP)"));
#endif
#ifdef CB_HAVE_SICONOS
    registry.add("siconos-lemke",
                 applies_to(siconos_lemke_entry(), "any J with at most max_rows rows (dense dual LCP)"));
    registry.add("siconos-nsn", applies_to(siconos_nsn_entry(), "any J (global problem, mu = 0)"));
#endif
#ifdef CB_HAVE_PETSC
    registry.add("tao-pdipm", applies_to(tao_pdipm_entry(), "any J (interior point on the primal QP)"));
    registry.add("tao-tron", applies_to(tao_tron_entry(), "bounds only (every row of J has at most one nonzero)"));
#endif
#ifdef CB_HAVE_BULLET
    registry.add("bullet-dantzig",
                 applies_to(bullet_dantzig_entry(), "any J with at most max_rows rows (dense dual LCP)"));
#endif
}

}  // namespace cb
