// PLACEHOLDER: replaced by the real implementation of `contactbench generate`.
#include "harness/commands.hpp"

#include <iostream>

namespace cb {

int cmd_generate(const Args&)
{
    std::cerr << "contactbench generate: not implemented yet\n";
    return 1;
}

} // namespace cb
