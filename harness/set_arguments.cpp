#include "harness/set_arguments.hpp"

#include "solvers/core/types.hpp"

#include <cstdlib>

namespace cb {

nlohmann::json setting_from_text(const std::string& text)
{
    if (text == "true") return true;
    if (text == "false") return false;
    if (text.empty()) return text;
    char* end = nullptr;
    const long long as_int = std::strtoll(text.c_str(), &end, 10);
    if (end && *end == '\0') return as_int;
    const double as_double = std::strtod(text.c_str(), &end);
    if (end && *end == '\0') return as_double;
    return text;
}

nlohmann::json settings_from_assignments(const std::vector<std::string>& assignments)
{
    nlohmann::json out = nlohmann::json::object();
    for (const auto& a : assignments) {
        const auto eq = a.find('=');
        if (eq == std::string::npos || eq == 0) throw_input_error("--set", a, "expected key=value");
        out[a.substr(0, eq)] = setting_from_text(a.substr(eq + 1));
    }
    return out;
}

}  // namespace cb
