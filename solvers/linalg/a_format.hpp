#pragma once
/// How an AOperator (solvers/linalg/a_product.hpp) stores A for its products, and the common setting
/// `a_format`'s text for it. Apart from a_product.hpp so that the settings need not include it.
#include <string>

namespace cb {

enum class AFormat {
    CSR,   ///< A itself (Eigen's compressed rows: a value and a 32-bit column per nonzero)
    BSR,   ///< 3x3 blocks (a vertex's three DOFs): nine values and one 32-bit block column per block
    SBSR,  ///< BSR's upper block triangle only (A symmetric): about half the bytes; one thread
    AUTO,  ///< a request only (prepare() never settles on it): SBSR for a large A on one thread, else
           ///< BSR when A has the blocks, else CSR (AOperator::prepare)
};

/// The setting's text: "csr", "bsr", "sbsr" or "auto".
inline const char* to_string(AFormat format)
{
    switch (format) {
    case AFormat::CSR:
        return "csr";
    case AFormat::BSR:
        return "bsr";
    case AFormat::SBSR:
        return "sbsr";
    case AFormat::AUTO:
        break;
    }
    return "auto";
}

/// The format a setting's text names; false when it names none.
inline bool parse_a_format(const std::string& text, AFormat& format)
{
    for (const AFormat f : {AFormat::AUTO, AFormat::CSR, AFormat::BSR, AFormat::SBSR})
        if (text == to_string(f)) {
            format = f;
            return true;
        }
    return false;
}

}  // namespace cb
