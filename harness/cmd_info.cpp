// PLACEHOLDER: replaced by the real implementation of `contactbench info`.
#include "harness/commands.hpp"

#include <iostream>

namespace cb {

int cmd_info(const Args&)
{
    std::cerr << "contactbench info: not implemented yet\n";
    return 1;
}

} // namespace cb
