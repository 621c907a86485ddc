#pragma once
/// Collision decoupling (ALGORITHMS.md §1): keep at most one row per vertex so that JJ' is
/// diagonal. A problem transform applied by the harness, not a solver.
/// Ref: Li et al. 2015, Sec. 4 "collision decoupling".
#include "solvers/core/qp.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace cb {

enum class DecoupleOrder { AUTHORS, RANDOM, DEPTH };
DecoupleOrder decouple_order_from_string(const std::string& name);  ///< throws InputError
const char* to_string(DecoupleOrder order);

/// True when no two rows of J touch the same vertex (vertex = column / 3).
bool is_decoupled(const SpMat& J);

struct DecoupleReport {
    std::vector<int> kept_rows;  ///< indices into the original J, ascending
    bool already_decoupled = false;
    DecoupleOrder order = DecoupleOrder::AUTHORS;
    std::uint64_t seed = 0;
    long rows_before = 0, rows_after = 0;
};

/// Chooses the rows to keep. `contacts` may be empty (kinds then default to OTHER, depth
/// to c_i - J_i x0).
DecoupleReport decouple_rows(const QpView& qp, const ContactRows& contacts, DecoupleOrder order, std::uint64_t seed);

/// The QP restricted to the given rows of J (contacts metadata restricted too).
Qp select_rows(const Qp& qp, const std::vector<int>& rows);

/// The given rows of J and c only, into `J_out` and `c_out` (what select_rows() changes; A, b and
/// x0 stay the original's, so a caller can view them instead of copying them).
void select_constraint_rows(const Qp& qp, const std::vector<int>& rows, SpMat& J_out, Vec& c_out);

}  // namespace cb
