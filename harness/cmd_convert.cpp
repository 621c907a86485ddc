// `contactbench convert IN OUT`: IN is read by its content (format_sniff.hpp: a .qpsnap, a Matrix
// Market folder, an FCLIB file or a Siconos .dat); OUT by its name: .qpsnap, .hdf5/.h5 (FCLIB), else a folder.
// Every output is written atomically.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/length_scale.hpp"
#include "problems/fclib_io.hpp"
#include "problems/format_sniff.hpp"
#include "problems/matrix_market.hpp"
#include "problems/qpsnap.hpp"
#include "problems/siconos_dat.hpp"

#include <filesystem>
#include <iostream>

namespace cb {
namespace {

const char* const CONVERT_USAGE =
    "contactbench convert IN OUT [--drop-friction] [--symmetrise] [--length-scale L]\n"
    "  IN.qpsnap  -> OUT folder (A.mtx b.mtx J.mtx c.mtx x0.mtx meta.json [contact.json x_ref.mtx lambda_ref.mtx]\n"
    "                [mu.mtx T.mtx cT.mtx h.mtx v0.mtx]: a frictional snapshot's friction in files of its own)\n"
    "  IN folder  -> OUT.qpsnap (Matrix Market files as written by scipy.io.mmwrite, Julia, MATLAB ...)\n"
    "  IN.qpsnap  -> OUT.qpsnap (rewrites; validates on the way)\n"
    "  IN.qpsnap  -> OUT.hdf5 / .h5: an FCLIB fclib_global problem (mu and tangents of a frictional snapshot,\n"
    "                otherwise mu = 0; /solution when known and frictionless)\n"
    "  IN FCLIB   -> OUT: an fclib_global or fclib_local file as Siconos, LMGC90 or libfclib write it\n"
    "               (global: A = M, b = f, J = H's normal columns', c = -w_N; local: A = W_NN, b = -q_N, J = I)\n"
    "  IN.dat     -> OUT: a Siconos numerics text dump: a local friction-contact problem (dense or sparse-block W)\n"
    "               as FCLIB local, or an LCP (A = M, b = -q, J = I)\n"
    "  --drop-friction  a frictional FCLIB or .dat problem (mu != 0) keeps its normal part (in meta.provenance);\n"
    "                   without it a global FCLIB one keeps its friction (.qpsnap version 2, .hdf5 or a\n"
    "                   folder's mu.mtx T.mtx cT.mtx) and a local one (no A to hold it) is refused\n"
    "  --symmetrise     an FCLIB or .dat matrix not symmetric to rounding is averaged with its transpose (recorded)\n"
    "  --length-scale L stores the problem's scene size l in the snapshot (meta.length_scale)\n"
    "IN is recognised by its content, not its name. Values are written with %.17g: .qpsnap -> folder ->\n"
    ".qpsnap keeps every array bit for bit; FCLIB keeps A, b, x0, J, c bit for bit but not per-row contact\n"
    "metadata (kinds, depths, vertices), so a .qpsnap -> FCLIB -> .qpsnap trip changes the content hash";

bool ends_with(const std::string& s, const std::string& tail)
{
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

int cmd_convert(const Args& args)
{
    const CommandLine cl("convert", args, {"--length-scale"}, {"--drop-friction", "--symmetrise"});
    if (cl.help()) {
        std::cout << "usage: " << CONVERT_USAGE << "\n";
        return 0;
    }
    cl.expect_positional(2, 2, CONVERT_USAGE);
    const std::string in = cl.positional()[0], out = cl.positional()[1];
    Qp qp;
    SnapshotExtras extras;
    const FileFormat format = sniff_format(in);
    FclibReadOptions options;
    options.drop_friction = cl.has("--drop-friction");
    options.symmetrise = cl.has("--symmetrise");
    // A global file's friction goes into every output: the snapshot (version 2), an FCLIB file or
    // a Matrix Market folder's friction files.
    options.keep_friction = true;
    if ((options.drop_friction || options.symmetrise) && format != FileFormat::FCLIB_GLOBAL &&
        format != FileFormat::FCLIB_LOCAL && format != FileFormat::SICONOS_DAT)
        throw_input_error(in, options.drop_friction ? "--drop-friction" : "--symmetrise",
                          "applies to FCLIB and Siconos .dat files only; this is " + format_name(format));
    if (format == FileFormat::MATRIX_MARKET_FOLDER || format == FileFormat::FOLDER) {
        qp = read_matrix_market_folder(in, &extras);
    } else if (format == FileFormat::FCLIB_GLOBAL || format == FileFormat::FCLIB_LOCAL || format == FileFormat::HDF5 ||
               format == FileFormat::SICONOS_DAT ||
               (format == FileFormat::UNKNOWN && is_fclib_path(in))) {  // a damaged .hdf5: the HDF5 reader says why
        qp = format == FileFormat::SICONOS_DAT ? read_siconos_dat_qp(in, options) : read_fclib(in, &extras, options);
        const nlohmann::json provenance = qp.meta.value("provenance", nlohmann::json::object());
        if (provenance.contains("dropped_friction"))
            std::cout << "dropped friction: mu in [" << provenance["dropped_friction"]["mu_min"] << ", "
                      << provenance["dropped_friction"]["mu_max"] << "] on " << provenance["contacts"]
                      << " contacts; the QP is the normal part (recorded in meta.provenance)\n";
        if (provenance.contains("friction"))
            std::cout << "kept friction: mu in [" << provenance["friction"]["mu_min"] << ", "
                      << provenance["friction"]["mu_max"] << "] on " << provenance["contacts"]
                      << " contacts; tangents T = H_T', cT = -w_T (recorded in meta.provenance)\n";
        if (provenance.contains("matrices")) std::cout << "matrices: " << provenance["matrices"].dump() << "\n";
    } else {
        expect_qpsnap(in, "convert");  // names a .dat, .npy or single .mtx
        qp = read_qpsnap(in, &extras);
    }
    // The problem's scene size (docs/accuracy.md "Length scale"), for a problem without geometry
    // whose user knows it: every later solve, run and judge uses it (length_scale_source "snapshot").
    if (cl.has("--length-scale")) qp.meta["length_scale"] = parse_length_scale("convert", cl.value("--length-scale"));
    if (is_fclib_path(out)) {
        write_fclib_global(out, qp, &extras);
        std::cout << "wrote " << out << " (FCLIB fclib_global, n = " << qp.n() << ", " << qp.m() << " contacts, "
                  << (qp.friction.mu.size() > 0 ? "with friction" : "mu = 0") << ")\n";
    } else if (ends_with(out, ".qpsnap")) {
        write_qpsnap(out, qp, &extras);
        std::cout << "wrote " << out << " (n = " << qp.n() << ", m = " << qp.m() << ", nnz(A) = " << qp.A.nonZeros()
                  << ", hash " << qpsnap_content_hash(out) << ")\n";
    } else {
        write_matrix_market_folder(out, qp, &extras);
        std::cout << "wrote " << out << "/ (n = " << qp.n() << ", m = " << qp.m() << ", nnz(A) = " << qp.A.nonZeros()
                  << (qp.friction.mu.size() ? ", friction in mu.mtx T.mtx" : "") << ")\n";
    }
    return 0;
}

}  // namespace cb
