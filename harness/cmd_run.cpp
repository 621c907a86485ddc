// PLACEHOLDER: replaced by the real implementation of `contactbench run`.
#include "harness/commands.hpp"

#include <iostream>

namespace cb {

int cmd_run(const Args&)
{
    std::cerr << "contactbench run: not implemented yet\n";
    return 1;
}

} // namespace cb
