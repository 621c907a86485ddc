#pragma once
/// Readers for a solution point (x, and optionally lambda) written by any program, checked
/// against the snapshot it answers. A SOLUTION is
///   a folder   x.{mtx,npy,txt} required, lambda.{mtx,npy,txt} optional (what `solve
///              --save-solution` writes, and what a `command` solver writes into {out});
///              lambda_t.{mtx,npy,txt} optional, the 2m tangential multipliers of a frictional
///              snapshot (rows 2i, 2i+1 of its T), refused on a snapshot without tangent rows
///   a file     x alone, by extension: .npy (numpy, float64/float32, shape (n,) or (n, 1)),
///              .mtx (Matrix Market array or coordinate vector), anything else plain text
///              (numbers separated by white space, commas allowed, `#` starts a comment).
/// Every error is an InputError naming the file and the field ("x.npy: x: expected 12 entries
/// (n of the snapshot), got 11"; "x.txt: x[3]: not finite (nan)").
#include "solvers/core/types.hpp"

#include <string>

namespace cb {

struct SolutionPoint {
    Vec x;
    Vec lambda;                 ///< empty when the solution has none
    Vec lambda_t;               ///< tangential multipliers (2m); empty when the solution has none
    std::string x_path;         ///< the file x came from
    std::string lambda_path;    ///< empty when there is no lambda
    std::string lambda_t_path;  ///< empty when there is no lambda_t
};

/// One vector from a file (format by extension, as above); `field` names it in messages; values
/// must be finite. With `expected` >= 0 (n for x, m for lambda) a file holding or declaring
/// another count is refused before anything is allocated; with -1 the size is not checked and a
/// .mtx coordinate vector may declare any size (callers that know n should pass it).
Vec read_vector_file(const std::string& path, const std::string& field, long expected = -1);

/// The file `stem`.{mtx,npy,txt} in `dir`; "" when none exists. Two of them is an error (which
/// one the program meant is unknown).
std::string find_vector_file(const std::string& dir, const std::string& stem);

/// x (size n) and, when present, lambda (size m) and lambda_t (size `tangent_rows`) of a SOLUTION
/// folder or file. `lambda_file` and `lambda_t_file` (optional) override the folder's.
/// `tangent_rows` is the snapshot's rows of T (2m with friction, else 0): a lambda_t on a snapshot
/// without them is an InputError naming it.
SolutionPoint read_solution(const std::string& path, long n, long m, const std::string& lambda_file = "",
                            const std::string& lambda_t_file = "", long tangent_rows = 0);

}  // namespace cb
