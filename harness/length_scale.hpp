#pragma once
/// The scene size l of a problem, fixed once before any solver runs so that every solver's stop
/// test and the harness's measure use the same one (docs/accuracy.md "Length scale").
#include "solvers/core/qp.hpp"

#include <string>

namespace cb {

/// A scene size given by the user: `--length-scale L` (source "given") or a suite's
/// `length_scale` (source "suite"); value 0 when none was given.
struct GivenLength {
    double value = 0.0;
    std::string source;
};

/// A key of the QP's content (A, b, J, c, x0 and meta) for the reference cache of a problem that
/// has no file (the stress cases).
std::string qp_content_key(const Qp& qp);

/// Parses a --length-scale value (a finite number > 0); InputError naming `where` and the option.
double parse_length_scale(const std::string& where, const std::string& text);

/// Sets qp.length, in this order:
///   1. `given` (value > 0);
///   2. the snapshot's meta.length_scale (source "snapshot"; not a finite number > 0: InputError
///      naming `where` and the field);
///   3. nothing when x0 has an extent (a start with geometry: accuracy_scale takes x0's extent,
///      at no cost);
///   4. the extent of the reference solution x* of the QP (harness/reference.hpp, cached under
///      `key`, computed with the provisional scale of 5): "reference_extent";
///   5. when x* is a point or the reference failed: |D^-1 (b - A x0)|_inf, the distance the load
///      moves each DOF alone from the start ("load_displacement"); 0 leaves accuracy_scale's
///      last fallbacks.
/// `cache` as for reference_solution ("" = cache_dir()).
void fix_length_scale(Qp& qp, const std::string& where, const std::string& key, const GivenLength& given,
                      const std::string& cache = "");

}  // namespace cb
