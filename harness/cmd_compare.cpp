// PLACEHOLDER: replaced by the real implementation of `contactbench compare`.
#include "harness/commands.hpp"

#include <iostream>

namespace cb {

int cmd_compare(const Args&)
{
    std::cerr << "contactbench compare: not implemented yet\n";
    return 1;
}

} // namespace cb
