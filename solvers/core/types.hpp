#pragma once
/// Basic types shared by every part of contactbench.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <stdexcept>
#include <string>

namespace cb {

/// Compressed sparse row matrix (A and J are stored row-major, as in the .qpsnap file).
using SpMat = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
/// Column-major sparse matrix, for CHOLMOD and column-wise algorithms.
using SpMatCol = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using Vec = Eigen::VectorXd;
using Triplet = Eigen::Triplet<double>;

/// Bad input (file, JSON, settings): the message names the file and the field.
/// The command line maps it to exit status 2.
class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Throws InputError("where: field: problem"); `where` is a file or a settings context.
[[noreturn]] inline void throw_input_error(const std::string& where, const std::string& field,
                                           const std::string& problem)
{
    std::string message = where;
    if (!field.empty()) message += (message.empty() ? "" : ": ") + field;
    throw InputError(message + ": " + problem);
}

}  // namespace cb
