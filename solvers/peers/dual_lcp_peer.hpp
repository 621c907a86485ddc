#pragma once
/// The one solve of the peers that pivot on the harness's dual LCP (siconos-lemke,
/// bullet-dantzig): refuse m > max_rows (not_applicable), form W and q with CHOLMOD as setup
/// (solvers/linalg/dual_lcp.hpp), answer m = 0 without the library, run the library in a child process
/// (a crash is a status, time_limit_s ends it), read back lambda and the report, form
/// x = A^-1 (b + J'lambda) and let the accuracy measure decide (finish_siconos_result). Only the
/// child's work and a few words differ between the peers.
#include "solvers/core/solver.hpp"
#include "solvers/peers/siconos_report.hpp"

#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

namespace cb {

/// What one dual-LCP peer brings.
struct DualLcpPeer {
    std::string name;     ///< the registry name, first word of every message ("siconos-lemke")
    std::string library;  ///< the library in messages ("Siconos": "the Siconos child process")
    std::string method;   ///< the finisher's `what` ("Siconos Lemke")
    std::string steps;    ///< the finisher's `steps` ("pivots")
    long max_rows = 4000;
    bool steps_are_pivots = false;   ///< also count the steps as counters.pivots
    bool residual_from_lcp = false;  ///< the library reports no residual: the LCP's natural one, here
    /// In the child: solves (W, q) (its own copies) and returns encode_child_reply(lambda, report).
    std::function<std::vector<char>(Eigen::MatrixXd& W, Vec& q)> run;
};

/// The child's reply: m doubles of lambda, then the report.
std::vector<char> encode_child_reply(const double* lambda, size_t m, const SiconosReport& report);

/// Solves `qp` with `peer` (see above). `result` comes with the peer's info facts filled in.
SolverResult solve_dual_lcp_peer(const QpView& qp, const SolveContext& context, const CommonSettings& common,
                                 const DualLcpPeer& peer, SolverResult result);

}  // namespace cb
