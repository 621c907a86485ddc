// `contactbench generate FAMILY --out FILE.qpsnap [--seed S] [--param key=value ...]`: writes one
// seeded synthetic snapshot (problems/synthetic.hpp); --list prints every family and its params.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "problems/io_util.hpp"
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"

#include <iostream>

namespace cb {
namespace {

const char* const GENERATE_USAGE = "contactbench generate FAMILY --out FILE.qpsnap [--seed S] [--param key=value ...]\n"
                                   "       contactbench generate --list            (families and their parameters)\n"
                                   "       contactbench generate FAMILY --help     (one family's parameters)\n"
                                   "  values are JSON: --param nx=8 --param youngs=1e9 --param rotate=false";

void print_list(std::ostream& out)
{
    out << "usage: " << GENERATE_USAGE << "\n\nfamilies:\n";
    for (const auto& f : synthetic_families()) out << "\n" << synthetic_family_help(f);
}

}  // namespace

int cmd_generate(const Args& args)
{
    const CommandLine cl("generate", args, {"--out", "--seed", "--param"}, {"--list"});
    if (cl.has("--list") || (cl.help() && cl.positional().empty())) {
        print_list(std::cout);
        return 0;
    }
    if (cl.help()) {
        std::cout << "usage: " << GENERATE_USAGE << "\n\n" << synthetic_family_help(cl.positional()[0]);
        return 0;
    }
    cl.expect_positional(1, 1, GENERATE_USAGE);
    const std::string family = cl.positional()[0];
    if (!cl.has("--out"))
        throw_input_error("generate", "--out",
                          "missing (the .qpsnap file to write)\nusage: " + std::string(GENERATE_USAGE));
    const long seed = cl.integer("--seed", 0);
    if (seed < 0) throw_input_error("generate", "--seed", "expected an integer >= 0, got " + std::to_string(seed));
    nlohmann::json params = nlohmann::json::object();
    for (const auto& kv : cl.values("--param")) {
        const auto eq = kv.find('=');
        if (eq == std::string::npos || eq == 0)
            throw_input_error("generate", "--param", "expected key=value, got '" + kv + "'");
        const std::string key = kv.substr(0, eq), text = kv.substr(eq + 1);
        try {
            check_json_depth(text.data(), text.data() + text.size(), "generate", "--param " + key);
            params[key] = nlohmann::json::parse(text);
        } catch (const nlohmann::json::exception&) {
            throw_input_error("generate", "--param " + key, "value '" + text + "' is not a JSON number or true/false");
        }
    }
    // Bounded parameters, finite values (problems/synthetic.hpp): never a file our reader rejects.
    const Qp qp = make_synthetic(family, params, std::uint64_t(seed));
    const std::string out = cl.path("--out");
    write_qpsnap(out, qp);
    long violated = 0;
    if (qp.m()) violated = long(((qp.J * qp.x0 - qp.c).array() < 0).count());
    std::cout << "wrote " << out << ": family " << family << ", seed " << seed << ", n = " << qp.n()
              << ", m = " << qp.m() << ", nnz(A) = " << qp.A.nonZeros() << ", violated at x0 = " << violated
              << ", hash " << qpsnap_content_hash(out) << "\n";
    return 0;
}

}  // namespace cb
