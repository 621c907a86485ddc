// PLACEHOLDER: replaced by the real implementation of `contactbench merge`.
#include "harness/commands.hpp"

#include <iostream>

namespace cb {

int cmd_merge(const Args&)
{
    std::cerr << "contactbench merge: not implemented yet\n";
    return 1;
}

} // namespace cb
