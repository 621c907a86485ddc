// PLACEHOLDER: replaced by the real implementation of `contactbench convert`.
#include "harness/commands.hpp"

#include <iostream>

namespace cb {

int cmd_convert(const Args&)
{
    std::cerr << "contactbench convert: not implemented yet\n";
    return 1;
}

} // namespace cb
