// `contactbench info SNAP [--json]`: what a snapshot holds (after full validation): sizes,
// header, contact kinds, row nnz histograms, meta and the content hash.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "problems/fclib_io.hpp"
#include "problems/format_sniff.hpp"
#include "problems/matrix_market.hpp"
#include "problems/qpsnap.hpp"
#include "problems/siconos_dat.hpp"

#include <chrono>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <map>

namespace cb {
namespace {

const char* const INFO_USAGE = "contactbench info SNAP [--json] [--time]\n"
                               "  SNAP: a .qpsnap file or a Matrix Market folder (A.mtx b.mtx J.mtx c.mtx x0.mtx);\n"
                               "        an FCLIB file (HDF5) or Siconos .dat is summarised (kind, contacts, mu)\n"
                               "  --json: print one JSON object instead of text\n"
                               "  --time: also time the validated load (read_qpsnap / the folder reader), wall and CPU";

const char* kind_name(std::int64_t k)
{
    switch (ContactKind(k)) {
    case ContactKind::PLANE:
        return "plane";
    case ContactKind::OBSTACLE:
        return "obstacle";
    case ContactKind::INTER_BODY:
        return "inter_body";
    case ContactKind::SELF:
        return "self";
    case ContactKind::OTHER:
        return "other";
    }
    return "unknown";
}

nlohmann::json row_histogram(const SpMat& M)
{
    std::map<long, long> h;
    for (Eigen::Index r = 0; r < M.rows(); ++r) ++h[long(M.outerIndexPtr()[r + 1] - M.outerIndexPtr()[r])];
    nlohmann::json out = nlohmann::json::object();
    for (const auto& kv : h) out[std::to_string(kv.first)] = kv.second;
    return out;
}

}  // namespace

int cmd_info(const Args& args)
{
    const CommandLine cl("info", args, {}, {"--json", "--time"});
    if (cl.help()) {
        std::cout << "usage: " << INFO_USAGE << "\n";
        return 0;
    }
    cl.expect_positional(1, 1, INFO_USAGE);
    const std::string path = cl.positional()[0];
    // By content: an FCLIB file is summarised (convert makes it a snapshot), other formats named.
    const FileFormat format = sniff_format(path);
    if (format == FileFormat::FCLIB_GLOBAL || format == FileFormat::FCLIB_LOCAL || format == FileFormat::HDF5 ||
        format == FileFormat::SICONOS_DAT) {
        nlohmann::json fclib = format == FileFormat::SICONOS_DAT ? describe_siconos_dat(path) : describe_fclib(path);
        fclib["path"] = path;  // its "convert" (and "friction_solve") say what those commands do with it
        if (cl.has("--json")) {
            std::cout << fclib.dump(2) << "\n";
            return 0;
        }
        std::cout << "file:        " << path << " (" << format_name(format) << ")\n";
        for (auto it = fclib.begin(); it != fclib.end(); ++it)
            if (it.key() != "path") std::cout << it.key() << ": " << it.value().dump() << "\n";
        return 0;
    }
    const bool folder = format == FileFormat::MATRIX_MARKET_FOLDER || format == FileFormat::FOLDER;
    if (!folder) expect_qpsnap(path, "info");
    nlohmann::json info;
    info["path"] = path;
    SnapshotExtras extras;
    const nlohmann::json header = folder ? nlohmann::json() : read_qpsnap_header(path);
    // Times the validated load alone (not the header peek, the hash or the statistics). One
    // initialisation, no assignment: Eigen 3.4's SparseMatrix has no move assignment.
    const auto wall0 = std::chrono::steady_clock::now();
    const std::clock_t cpu0 = std::clock();
    const Qp qp = folder ? read_matrix_market_folder(path, &extras) : read_qpsnap(path, &extras);
    const double load_cpu = double(std::clock() - cpu0) / CLOCKS_PER_SEC;
    const double load_wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    if (folder) {
        info["format"] = "matrix-market folder";
    } else {
        info["format"] = "qpsnap";
        info["version"] = header["version"];
        info["hash"] = qpsnap_content_hash(path);
        info["file_bytes"] = std::filesystem::file_size(path);
        nlohmann::json arrays = nlohmann::json::object();
        for (auto it = header["arrays"].begin(); it != header["arrays"].end(); ++it)
            arrays[it.key()] = {
                {"dtype", it.value()["dtype"]}, {"shape", it.value()["shape"]}, {"nbytes", it.value()["nbytes"]}};
        info["arrays"] = arrays;
    }
    if (cl.has("--time")) info["load_time"] = {{"wall_s", load_wall}, {"cpu_s", load_cpu}};
    info["n"] = qp.n();
    info["m"] = qp.m();
    info["nnz_A"] = qp.A.nonZeros();
    info["nnz_J"] = qp.J.nonZeros();
    const Vec diag = qp.A.diagonal();
    info["A_diagonal"] = {{"min", diag.size() ? diag.minCoeff() : 0.0}, {"max", diag.size() ? diag.maxCoeff() : 0.0}};
    info["A_row_nnz_histogram"] = row_histogram(qp.A);
    info["J_row_nnz_histogram"] = row_histogram(qp.J);
    nlohmann::json kinds = nlohmann::json::object();
    for (const auto k : qp.contacts.kind) kinds[kind_name(k)] = kinds.value(kind_name(k), 0) + 1;
    info["contact_kinds"] = kinds;
    const Vec r = qp.m() ? Vec(qp.J * qp.x0 - qp.c) : Vec();
    info["violated_at_x0"] = qp.m() ? long((r.array() < 0).count()) : 0L;
    info["max_violation_at_x0"] = qp.m() ? std::max(0.0, -r.minCoeff()) : 0.0;
    info["has_x_ref"] = extras.x_ref.size() > 0;
    info["has_lambda_ref"] = extras.lambda_ref.size() > 0;
    // Coulomb friction (snapshot version 2); a file without it is the frictionless problem, mu = 0.
    const Friction& fr = qp.friction;
    nlohmann::json friction = {{"mu_min", fr.mu.size() ? fr.mu.minCoeff() : 0.0},
                               {"mu_max", fr.mu.size() ? fr.mu.maxCoeff() : 0.0},
                               {"frictional_contacts", long((fr.mu.array() > 0).count())},
                               {"tangent_rows", long(fr.T.rows())},
                               {"nnz_T", long(fr.T.nonZeros())},
                               {"has_cT", fr.cT.size() > 0},
                               {"h", fr.h > 0 ? nlohmann::json(fr.h) : nlohmann::json()},
                               {"has_v0", fr.v0.size() > 0}};
    info["friction"] = friction;
    info["meta"] = qp.meta;
    if (cl.has("--json")) {
        std::cout << info.dump(2) << "\n";
        return 0;
    }
    std::cout << "file:        " << path << " (" << info["format"].get<std::string>();
    if (!folder) std::cout << " v" << info["version"] << ", " << info["file_bytes"] << " bytes";
    std::cout << ")\n";
    if (!folder) std::cout << "hash:        " << info["hash"].get<std::string>() << "\n";
    std::cout << "n:           " << qp.n() << "\nm:           " << qp.m() << "\nnnz(A):      " << qp.A.nonZeros()
              << "\nnnz(J):      " << qp.J.nonZeros() << "\ndiag(A):     [" << info["A_diagonal"]["min"] << ", "
              << info["A_diagonal"]["max"] << "]\n";
    std::cout << "contacts:    ";
    if (kinds.empty()) std::cout << "no kinds recorded";
    for (auto it = kinds.begin(); it != kinds.end(); ++it) std::cout << it.key() << " " << it.value() << "  ";
    std::cout << "\nat x0:       " << info["violated_at_x0"] << " violated rows, max violation "
              << info["max_violation_at_x0"] << "\n";
    auto print_hist = [](const char* name, const nlohmann::json& h) {
        std::cout << name;
        for (auto it = h.begin(); it != h.end(); ++it) std::cout << " " << it.key() << ":" << it.value();
        std::cout << "   (nnz:rows)\n";
    };
    std::cout << "friction:    ";
    if (fr.mu.size() == 0)
        std::cout << "none (mu = 0)";
    else
        std::cout << "mu in [" << friction["mu_min"] << ", " << friction["mu_max"] << "], "
                  << friction["frictional_contacts"] << " of " << qp.m() << " contacts with mu > 0, T " << fr.T.rows()
                  << " x " << fr.T.cols() << " (" << fr.T.nonZeros() << " nonzeros)" << (fr.cT.size() ? ", cT" : "");
    if (fr.h > 0) std::cout << ", h " << friction["h"] << (fr.v0.size() ? ", v0" : "");
    std::cout << "\n";
    print_hist("row nnz A:  ", info["A_row_nnz_histogram"]);
    print_hist("row nnz J:  ", info["J_row_nnz_histogram"]);
    if (info.contains("arrays")) {
        std::cout << "arrays:\n";
        for (auto it = info["arrays"].begin(); it != info["arrays"].end(); ++it)
            std::cout << "  " << it.key() << "  " << it.value()["dtype"].get<std::string>() << " "
                      << it.value()["shape"].dump() << "  " << it.value()["nbytes"] << " bytes\n";
    }
    std::cout << "meta:        " << qp.meta.dump(2) << "\n";
    if (cl.has("--time"))
        std::cout << "load time:   " << load_wall << " s wall, " << load_cpu << " s cpu (read + validation)\n";
    return 0;
}

}  // namespace cb
