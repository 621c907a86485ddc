// suites/friction.json (issue 48 item 6): it parses, names only solvers this build registers (an
// optional entry only a peer of a library this build may lack) with settings they accept, and
// every label takes the friction but the one frictionless reference the suite's description names.
#include "harness/suite.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/peers/siconos_fc3d.hpp"

#include <gtest/gtest.h>
#include <set>
#include <string>

using namespace cb;

namespace {

const std::string SUITE = std::string(CB_SOURCE_DIR) + "/suites/friction.json";

}  // namespace

TEST(FrictionSuiteFile, ParsesWithItsTolerancesAndFrames)
{
    const Suite suite = load_suite(SUITE);
    EXPECT_EQ(suite.name, "friction");
    EXPECT_EQ(suite.tol, 1e-8);  // plots/friction_suite.py runs it at 1e-4 and 1e-8
    ASSERT_EQ(suite.simulations.size(), 3u);
    std::set<std::string> scenes;
    for (const SuiteSimulation& sim : suite.simulations) scenes.insert(sim.scene);
    EXPECT_EQ(scenes, (std::set<std::string>{"../scenes/friction_incline.json", "../scenes/friction_slide.json",
                                             "../scenes/two_dinos_1303_friction.json"}));
    EXPECT_EQ(suite.snapshots, (std::vector<std::string>{"../results/friction/fclib"}));
}

TEST(FrictionSuiteFile, NamesOnlyRegisteredSolversThatTakeTheFriction)
{
    const Suite suite = load_suite(SUITE);
    const SolverRegistry& registry = builtin_registry();
    std::set<std::string> frictionless;
    for (const SuiteSolver& s : suite.solvers) {
        SCOPED_TRACE(s.label);
        if (s.optional) {
            // only Siconos' peers may be missing, and only from a build without Siconos
            EXPECT_EQ(s.solver.rfind("siconos-", 0), 0u);
            if (!siconos_fc3d_built()) continue;
        }
        ASSERT_TRUE(registry.contains(s.solver)) << s.solver << " is not registered";
        const auto solver = registry.create(s.solver, s.settings);  // throws on a setting it does not take
        if (!solver->handles_friction()) frictionless.insert(s.label);
    }
    EXPECT_EQ(frictionless, (std::set<std::string>{"mprgp-coupled"}));
}
