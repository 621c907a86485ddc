// `contactbench convert IN OUT`: .qpsnap <-> Matrix Market folder, the direction by the names:
// OUT ending in .qpsnap is written as a snapshot, anything else as a folder; IN that is a folder
// is read as Matrix Market, anything else as a .qpsnap. Both outputs are written atomically.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/length_scale.hpp"
#include "problems/fclib_io.hpp"
#include "problems/matrix_market.hpp"
#include "problems/qpsnap.hpp"

#include <filesystem>
#include <iostream>

namespace cb {
namespace {

const char* const USAGE =
    "contactbench convert IN OUT [--length-scale L]\n"
    "  IN.qpsnap  -> OUT folder (A.mtx b.mtx J.mtx c.mtx x0.mtx meta.json [contact.json x_ref.mtx lambda_ref.mtx])\n"
    "  IN folder  -> OUT.qpsnap (Matrix Market files as written by scipy.io.mmwrite, Julia, MATLAB ...)\n"
    "  IN.qpsnap  -> OUT.qpsnap (rewrites; validates on the way)\n"
    "  IN.qpsnap  -> OUT.hdf5 / .h5: an FCLIB fclib_global problem (mu = 0; /solution when known), and back\n"
    "--length-scale L: stores the problem's scene size l in the snapshot (meta.length_scale)\n"
    "values are written with %.17g: .qpsnap -> folder -> .qpsnap keeps every array bit for bit";

bool ends_with(const std::string& s, const std::string& tail)
{
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

int cmd_convert(const Args& args)
{
    const CommandLine cl("convert", args, {"--length-scale"}, {});
    if (cl.help()) {
        std::cout << "usage: " << USAGE << "\n";
        return 0;
    }
    cl.expect_positional(2, 2, USAGE);
    const std::string in = cl.positional()[0], out = cl.positional()[1];
    Qp qp;
    SnapshotExtras extras;
    if (std::filesystem::is_directory(in))
        qp = read_matrix_market_folder(in, &extras);
    else if (is_fclib_path(in))
        qp = read_fclib_global(in, &extras);
    else
        qp = read_qpsnap(in, &extras);
    // The problem's scene size (docs/accuracy.md "Length scale"), for a problem without geometry
    // whose user knows it: every later solve, run and judge uses it (length_scale_source "snapshot").
    if (cl.has("--length-scale")) qp.meta["length_scale"] = parse_length_scale("convert", cl.value("--length-scale"));
    if (is_fclib_path(out)) {
        write_fclib_global(out, qp, &extras);
        std::cout << "wrote " << out << " (FCLIB fclib_global, n = " << qp.n() << ", " << qp.m()
                  << " contacts, mu = 0)\n";
    } else if (ends_with(out, ".qpsnap")) {
        write_qpsnap(out, qp, &extras);
        std::cout << "wrote " << out << " (n = " << qp.n() << ", m = " << qp.m() << ", nnz(A) = " << qp.A.nonZeros()
                  << ", hash " << qpsnap_content_hash(out) << ")\n";
    } else {
        write_matrix_market_folder(out, qp, &extras);
        std::cout << "wrote " << out << "/ (n = " << qp.n() << ", m = " << qp.m() << ", nnz(A) = " << qp.A.nonZeros()
                  << ")\n";
    }
    return 0;
}

}  // namespace cb
