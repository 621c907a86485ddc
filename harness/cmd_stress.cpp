// PLACEHOLDER: replaced by the real implementation of `contactbench stress`.
#include "harness/commands.hpp"

#include <iostream>

namespace cb {

int cmd_stress(const Args&)
{
    std::cerr << "contactbench stress: not implemented yet\n";
    return 1;
}

} // namespace cb
