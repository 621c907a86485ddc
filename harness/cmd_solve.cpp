// PLACEHOLDER: replaced by the real implementation of `contactbench solve`.
#include "harness/commands.hpp"

#include <iostream>

namespace cb {

int cmd_solve(const Args&)
{
    std::cerr << "contactbench solve: not implemented yet\n";
    return 1;
}

} // namespace cb
