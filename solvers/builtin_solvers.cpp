// The list of built-in solvers: one line per solver (see README "Adding a solver").
#include "solvers/registry.hpp"

namespace cb {

void register_builtin_solvers(SolverRegistry& registry)
{
    (void)registry;
    // REGISTRATIONS (one line each, keep sorted):
}

} // namespace cb
