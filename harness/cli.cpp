#include "harness/cli.hpp"

#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>

namespace cb {

CommandLine::CommandLine(const std::string& command, const std::vector<std::string>& args,
                         const std::set<std::string>& value_options, const std::set<std::string>& flag_options)
    : m_command(command)
{
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--help" || a == "-h") {
            m_help = true;
        } else if (a.size() > 2 && a.compare(0, 2, "--") == 0) {
            std::string key = a, value;
            const auto eq = a.find('=');
            const bool inline_value = eq != std::string::npos;
            if (inline_value) {
                key = a.substr(0, eq);
                value = a.substr(eq + 1);
            }
            if (value_options.count(key)) {
                if (!inline_value) {
                    if (i + 1 >= args.size()) throw_input_error(m_command, key, "expects a value");
                    value = args[++i];
                }
                m_values[key].push_back(value);
            } else if (flag_options.count(key) && !inline_value) {
                m_flags.insert(key);
            } else {
                std::string known;
                for (const auto& o : value_options) known += " " + o;
                for (const auto& o : flag_options) known += " " + o;
                throw_input_error(m_command, key, "unknown option; known:" + known + " --help");
            }
        } else {
            m_positional.push_back(a);
        }
    }
}

std::string CommandLine::value(const std::string& option, const std::string& fallback) const
{
    const auto it = m_values.find(option);
    return it == m_values.end() ? fallback : it->second.back();
}

std::string CommandLine::path(const std::string& option, const std::string& fallback) const
{
    const auto it = m_values.find(option);
    if (it == m_values.end()) return fallback;
    if (it->second.back().empty()) throw_input_error(m_command, option, "expects a file or folder name, got \"\"");
    return it->second.back();
}

std::vector<std::string> CommandLine::values(const std::string& option) const
{
    const auto it = m_values.find(option);
    return it == m_values.end() ? std::vector<std::string>{} : it->second;
}

double CommandLine::number(const std::string& option, double fallback) const
{
    if (!m_values.count(option)) return fallback;
    const std::string v = value(option);
    char* end = nullptr;
    const double d = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0') throw_input_error(m_command, option, "expected a number, got '" + v + "'");
    // inf, nan and 1e999 parse, and no option means them: a tolerance or limit of inf is a typo.
    if (!std::isfinite(d)) throw_input_error(m_command, option, "expected a finite number, got '" + v + "'");
    return d;
}

long CommandLine::integer(const std::string& option, long fallback) const
{
    if (!m_values.count(option)) return fallback;
    const std::string v = value(option);
    char* end = nullptr;
    errno = 0;
    const long d = std::strtol(v.c_str(), &end, 10);
    if (v.empty() || *end != '\0') throw_input_error(m_command, option, "expected an integer, got '" + v + "'");
    if (errno == ERANGE)
        throw_input_error(m_command, option,
                          "'" + v + "' is out of range (at most " + std::to_string(LONG_MAX) + " in magnitude)");
    return d;
}

void CommandLine::expect_positional(size_t min, size_t max, const std::string& usage) const
{
    if (m_positional.size() < min || m_positional.size() > max)
        throw InputError(m_command + ": expected " +
                         (min == max ? std::to_string(min) : std::to_string(min) + ".." + std::to_string(max)) +
                         " arguments, got " + std::to_string(m_positional.size()) + "\nusage: " + usage);
}

}  // namespace cb
