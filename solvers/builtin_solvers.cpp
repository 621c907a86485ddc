// The list of built-in solvers: one line per solver (see README "Adding a solver").
#include "solvers/registry.hpp"
#include "solvers/active_set.hpp"
#include "solvers/cg.hpp"
#include "solvers/mprgp.hpp"
#include "solvers/mprgp_box.hpp"
#include "solvers/mprgp_coupled.hpp"
#include "solvers/ica.hpp"
#include "solvers/pgs.hpp"
#ifdef CB_HAVE_IPOPT
#include "solvers/peers/ipopt_solver.hpp"
#endif
#ifdef CB_HAVE_SICONOS
#include "solvers/peers/siconos_lemke.hpp"
#include "solvers/peers/siconos_nsn.hpp"
#endif

namespace cb {

void register_builtin_solvers(SolverRegistry& registry)
{
    (void)registry;
    // REGISTRATIONS (one line each, keep sorted):
    registry.add("active-set", active_set_entry());
    registry.add("cg", cg_entry());
    registry.add("mprgp", mprgp_entry());
    registry.add("mprgp-box", mprgp_box_entry());
    registry.add("mprgp-coupled", mprgp_coupled_entry());
    registry.add("ica", ica_entry());
    registry.add("pgs", pgs_entry());
    // External peers (solvers/peers/), each only when CMake found its library:
#ifdef CB_HAVE_IPOPT
    registry.add("ipopt", ipopt_entry());
#endif
#ifdef CB_HAVE_SICONOS
    registry.add("siconos-lemke", siconos_lemke_entry());
    registry.add("siconos-nsn", siconos_nsn_entry());
#endif
}

} // namespace cb
