// contactbench --version: the commit and build facts every results file records (provenance),
// plus the version of each library contactbench is built on.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/provenance.hpp"
#include "sim/simulator.hpp"  // SIMULATOR_VERSION

#include <nlohmann/json.hpp>
#include <iostream>

namespace cb {

int cmd_version(const Args& args)
{
    const CommandLine cl("--version", args, {}, {"--json"});
    if (cl.help()) {
        std::cout << "usage: contactbench --version [--json]\n"
                     "  the commit, build type, compiler and library versions (as recorded in results)\n";
        return 0;
    }
    cl.expect_positional(0, 0, "contactbench --version [--json]");
    const nlohmann::json& p = provenance();
    const std::string json_version = std::to_string(NLOHMANN_JSON_VERSION_MAJOR) + "." +
                                     std::to_string(NLOHMANN_JSON_VERSION_MINOR) + "." +
                                     std::to_string(NLOHMANN_JSON_VERSION_PATCH);
    auto text = [&](const char* key) {
        return p.contains(key) && p[key].is_string() ? p[key].get<std::string>() : "unknown";
    };
    if (cl.has("--json")) {
        nlohmann::json out = {{"git_commit", text("git_commit")}, {"git_dirty", p.value("git_dirty", nlohmann::json())},
                              {"build_type", text("build_type")}, {"compiler", text("compiler")},
                              {"eigen", text("eigen")},           {"suitesparse", text("suitesparse")},
                              {"nlohmann_json", json_version},    {"blas", text("blas")}};
        out["blas_threads"] = p.value("blas_threads", 0);
        out["simulator_version"] = sim::SIMULATOR_VERSION;  // what simulation.json records (tools/ladder.sh)
        out["peers"] = p.value("peers", nlohmann::json::object());
        std::cout << out.dump(1) << "\n";
        return 0;
    }
    const nlohmann::json dirty = p.value("git_dirty", nlohmann::json());
    std::cout << "contactbench " << text("git_commit")
              << (dirty.is_boolean() ? (dirty.get<bool>() ? " (uncommitted changes)" : "") : " (not a git checkout)")
              << "\n"
              << "build type    " << text("build_type") << "\n"
              << "compiler      " << text("compiler") << "\n"
              << "Eigen         " << text("eigen") << "\n"
              << "SuiteSparse   " << text("suitesparse") << "\n"
              << "nlohmann-json " << json_version << "\n"
              << "BLAS          " << text("blas") << " (" << p.value("blas_threads", 0)
              << " threads; 0: not OpenBLAS)\n";
    std::string peers;
    const nlohmann::json built = p.value("peers", nlohmann::json::object());
    for (const auto& peer : built.items())
        peers += (peers.empty() ? "" : ", ") + peer.key() + " (" + peer.value().get<std::string>() + ")";
    std::cout << "peers         " << (peers.empty() ? "none built (docs/peers.md)" : peers) << "\n";
    return 0;
}

}  // namespace cb
