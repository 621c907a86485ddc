// The list of built-in solvers: one line per solver (see README "Adding a solver").
#include "solvers/core/registry.hpp"
#include "solvers/friction/mprgp_bmf03.hpp"
#include "solvers/friction/mprgp_staggered.hpp"
#include "solvers/friction/mprgp_tresca_entries.hpp"
#include "solvers/friction/nsgs_friction.hpp"
#include "solvers/methods/active_set.hpp"
#include "solvers/methods/cg.hpp"
#include "solvers/methods/ica.hpp"
#include "solvers/methods/pgs.hpp"
#include "solvers/mprgp/mprgp.hpp"
#include "solvers/mprgp/mprgp_box.hpp"
#include "solvers/mprgp/mprgp_coupled.hpp"
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
#include "solvers/peers/siconos_friction.hpp"
#include "solvers/peers/siconos_lemke.hpp"
#include "solvers/peers/siconos_nsn.hpp"
#endif

namespace cb {

void register_builtin_solvers(SolverRegistry& registry)
{
    // REGISTRATIONS (one line each): registry.add("name", name_entry());
    registry.add("active-set", active_set_entry());
    registry.add("cg", cg_entry());
    registry.add("mprgp", mprgp_entry());
    registry.add("mprgp-box", mprgp_box_entry());
    registry.add("mprgp-coupled", mprgp_coupled_entry());  // applies to any J (the entry's default)
    registry.add("ica", ica_entry());
    registry.add("pgs", pgs_entry());
    registry.add("nsgs-friction", nsgs_friction_entry());            // pgs's frictional extension (Coulomb cones)
    registry.add("mprgp-tresca-fp", mprgp_tresca_fp_entry());        // Coulomb by a fixed point on Tresca bounds
    registry.add("mprgp+ica-friction", mprgp_ica_friction_entry());  // baseline: mprgp-box's r_n, then nsgs
    registry.add("mprgp+bmf03", mprgp_bmf03_entry());  // baseline: mprgp-coupled, then a Coulomb velocity update
    registry.add("mprgp-staggered", mprgp_staggered_entry());  // Kaufman et al. 2008 on mprgp-coupled and MPGP
    // External peers (solvers/peers/), each only when CMake found its library:
#ifdef CB_HAVE_IPOPT
    registry.add("ipopt", ipopt_entry());
#endif
#ifdef CB_HAVE_SICONOS
    registry.add("siconos-lemke", siconos_lemke_entry());
    registry.add("siconos-nsn", siconos_nsn_entry());
    registry.add("siconos-fc3d-nsgs", siconos_friction_entry("fc3d", "nsgs"));  // frictional, local form
    registry.add("siconos-fc3d-nsn", siconos_friction_entry("fc3d", "nsn"));
    registry.add("siconos-gfc3d-nsn", siconos_friction_entry("gfc3d", "nsn"));  // frictional, global form
#endif
#ifdef CB_HAVE_PETSC
    registry.add("tao-pdipm", tao_pdipm_entry());
    registry.add("tao-tron", tao_tron_entry());
#endif
#ifdef CB_HAVE_BULLET
    registry.add("bullet-dantzig", bullet_dantzig_entry());
#endif
}

}  // namespace cb
