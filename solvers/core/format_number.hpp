#pragma once
/// The one number formatter of messages, tables and error texts: printf's %.<digits>g or
/// %.<digits>e in the C locale (the same bytes as an ostream with that precision, and flag).
/// Infinities print as inf / -inf, NaN as printf prints it (nan or -nan).
#include <cstdio>
#include <string>

namespace cb {

/// %.<digits>g: `digits` significant digits, fixed or scientific, whichever is shorter.
inline std::string format_g(double v, int digits = 6)
{
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%.*g", digits, v);
    return buffer;
}

/// %.<digits>e: scientific, `digits` digits after the point.
inline std::string format_e(double v, int digits)
{
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%.*e", digits, v);
    return buffer;
}

}  // namespace cb
