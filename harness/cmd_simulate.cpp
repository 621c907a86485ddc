// PLACEHOLDER: replaced by the real implementation of `contactbench simulate`.
#include "harness/commands.hpp"

#include <iostream>

namespace cb {

int cmd_simulate(const Args&)
{
    std::cerr << "contactbench simulate: not implemented yet\n";
    return 1;
}

} // namespace cb
