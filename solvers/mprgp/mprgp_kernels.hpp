#pragma once
/// Closed-form MPRGP operators for a decoupled J (JJ' diagonal; ALGORITHMS.md §2) and the power
/// method that sets alpha_bar. Free functions, unit-testable without a solver.
/// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015,
///      eq. (13) reduced free gradient, eq. (15)-(16) free gradient, eq. (17)-(18) chopped
///      gradient, eq. (19)-(20) projection; Alg. 1-3.
#include "solvers/core/types.hpp"
#include "solvers/linalg/a_product.hpp"

#include <cstdint>
#include <vector>

namespace cb {

/// Row data of a decoupled J: s_i = ||J_i||^2 and, for the Jacobi preconditioner,
/// r_i = 1 / (J D^-1 J')_ii. Rows with s_i = 0 (zero rows) are never active.
struct DecoupledRows {
    Vec s;                         ///< #rows: ||J_i||^2
    Vec inv_s;                     ///< #rows: 1 / s_i, 0 for zero rows
    Vec r;                         ///< #rows: 1 / (J D^-1 J')_ii, 0 for zero rows
    std::vector<char> dof_in_row;  ///< #DOF: 1 when a row of J has a nonzero on the DOF
};

/// @param dinv  #DOF: 1 / diag(A) (or ones for no preconditioning)
DecoupledRows make_decoupled_rows(const SpMat& J, const Vec& dinv);

/// J_i v for one row (row-major J).
inline double row_dot(const SpMat& J, Eigen::Index i, const Vec& v)
{
    double s = 0.0;
    const int* outer = J.outerIndexPtr();
    const int* inner = J.innerIndexPtr();
    const double* val = J.valuePtr();
    for (int k = outer[i]; k < outer[i + 1]; ++k) s += val[k] * v[inner[k]];
    return s;
}

/// v += a J_i'
inline void row_axpy(const SpMat& J, Eigen::Index i, double a, Vec& v)
{
    const int* outer = J.outerIndexPtr();
    const int* inner = J.innerIndexPtr();
    const double* val = J.valuePtr();
    for (int k = outer[i]; k < outer[i + 1]; ++k) v[inner[k]] += a * val[k];
}

/// Active set A(x) = { i : |J_i x - c_i| <= tau_i } (zero rows never active).
void active_rows(const SpMat& J, const Vec& c, const DecoupledRows& rows, const Vec& x, std::vector<char>& active);

/// Projection (eq. 19, decoupled): lambda_i = max(0, (c_i - J_i x) / s_i), y = x + J' lambda.
/// @param[out] lambda  if not null, the projection multipliers
/// @return number of rows moved (lambda_i > 0)
long project_decoupled(const SpMat& J, const Vec& c, const DecoupledRows& rows, const Vec& x, Vec& y,
                       Vec* lambda = nullptr);

/// Free gradient (eq. 15-16): phi = g - sum_{i in A} (J_i g / s_i) J_i'.
void free_gradient(const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active, const Vec& g, Vec& phi);

/// Chopped gradient (eq. 17-18): beta = sum_{i in A} min(0, J_i g / s_i) J_i'.
void chopped_gradient(const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active, const Vec& g,
                      Vec& beta);

/// phitilde'phi with phitilde = (x - P(x - alpha_bar phi)) / alpha_bar (eq. 13), through one projection.
double reduced_free_gradient_dot(const SpMat& J, const Vec& c, const DecoupledRows& rows, const Vec& x, const Vec& phi,
                                 double alpha_bar);

/// Multipliers for the accuracy measure: lambda_i = max(0, J_i g / s_i) on active rows, 0 elsewhere.
void decoupled_multipliers(const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active, const Vec& g,
                           Vec& lambda);

/// D-weighted projection of D^-1 g onto the face: z = D^-1 g - W' mu, W = J D^-1,
/// mu_i = r_i (W g)_i on active rows, so that J_A z = 0 exactly (with JJ' diagonal).
/// @param dinv  1 / diag(A); `rows` must be built with the same dinv
void jacobi_face_precondition(const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active,
                              const Vec& dinv, const Vec& g, Vec& z);

/// Power method settings and result (ALGORITHMS.md §3 "Power method").
enum class PowerRule {
    POWER,    ///< stop when the estimate's relative change <= rel_change, warm start allowed
    AUTHORS,  ///< ||v_{k+1} - v_k|| <= tol, at most 1001 products, cold start
};
struct PowerResult {
    double estimate = 0.0;  ///< ||A v|| at the last unit vector v (approaches ||A||_2 from below)
    long products = 0;
    bool warm = false;  ///< started from the given vector
};
/// Estimates ||A||_2 for SPD A.
/// @param[in,out] v  start vector when warm (size n, nonzero); on output the last unit iterate
/// @param deadline_check  called every product; returns true to stop early (time limit)
PowerResult power_method(const AOperator& A, Vec& v, PowerRule rule, long max_products, double tol, bool warm,
                         std::uint64_t seed, bool (*deadline_check)(void*) = nullptr, void* deadline_data = nullptr);

/// An accepted CG step's pass over the DOFs: x -= alpha p, g -= alpha ap, phi = g, and the largest
/// |g_j| w_j (returned). AVX2 where the CPU has it: the same x, g and phi to the bit (a product,
/// then a difference, entry by entry), and a maximum is the same in any order.
double cg_step_pass(double alpha, const Vec& p, const Vec& ap, const Vec& w, Vec& x, Vec& g, Vec& phi);

/// Decoupled MPRGP's accepted CG step over the DOFs: x -= alpha p, g -= alpha ap, z = dinv .* g,
/// and over the DOFs in no row (in_row[j] == 0) the sums z'g, z'ap, g'g, added in DOF order as one
/// loop adds them, and the largest |g_j| w_j. AVX2 where the CPU has it: the entries' products and
/// differences in packets of four, each sum still one chain in DOF order (a skipped DOF adds +0.0,
/// which leaves a sum that started at +0.0 as it is), so the same bits as the plain loop.
struct CgUpdateSums {
    double zg = 0.0, zap = 0.0, gg = 0.0, ginf = 0.0;
};
CgUpdateSums cg_update_pass(double alpha, const Vec& p, const Vec& ap, const Vec& dinv, const Vec& w,
                            const char* in_row, Vec& x, Vec& g, Vec& z);

/// a'b and a'c in one pass over a (returned in ab, ac), each summed in the order of Eigen's
/// a.dot(b) (its packets, two partial packet sums, then the tail entry by entry): the same bits as
/// the two dots, with a read once instead of twice. a, b and c have one size.
void two_dots(const Vec& a, const Vec& b, const Vec& c, double& ab, double& ac);

}  // namespace cb
