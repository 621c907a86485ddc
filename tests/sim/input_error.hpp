#pragma once
/// The message of the InputError a call throws, or "(no error)": what the tests of bad input compare.
#include "problems/io_util.hpp"

#include <functional>
#include <string>

namespace cb::test {

inline std::string input_error_of(const std::function<void()>& f)
{
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

}  // namespace cb::test
