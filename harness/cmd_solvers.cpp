// contactbench solvers: every registered solver, one line each, with what it applies to.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "solvers/core/registry.hpp"

#include <nlohmann/json.hpp>
#include <algorithm>
#include <iostream>

namespace cb {

int cmd_solvers(const Args& args)
{
    const CommandLine cl("solvers", args, {}, {"--json"});
    const std::string usage = "usage: contactbench solvers [--json]\n"
                              "  every registered solver: name, applicability, description (settings: contactbench "
                              "solve --solver NAME --help)\n";
    if (cl.help()) {
        std::cout << usage;
        return 0;
    }
    cl.expect_positional(0, 0, usage);
    const SolverRegistry& registry = builtin_registry();
    const std::vector<std::string> names = registry.names();
    if (cl.has("--json")) {
        nlohmann::json out = nlohmann::json::array();
        for (const auto& name : names) {
            const SolverEntry& e = registry.entry(name);
            nlohmann::json settings = nlohmann::json::array();
            for (const auto& s : e.settings)
                settings.push_back({{"key", s.key}, {"default", s.default_value}, {"doc", s.doc}});
            // library: the external library and version of a peer ("" for the project's own solvers)
            out.push_back({{"name", name},
                           {"applies_to", e.applies_to},
                           {"description", e.description},
                           {"library", e.library},
                           {"needs_settings", e.needs_settings},  // command: runs only with its argv
                           {"settings", settings}});
        }
        std::cout << out.dump(1) << "\n";
        return 0;
    }
    size_t width = 0;
    for (const auto& name : names) width = std::max(width, name.size());
    for (const auto& name : names) {
        const SolverEntry& e = registry.entry(name);
        std::cout << name << std::string(width + 2 - name.size(), ' ') << "[" << e.applies_to << "] " << e.description
                  << "\n";
    }
    return 0;
}

}  // namespace cb
