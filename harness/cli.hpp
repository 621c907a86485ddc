#pragma once
/// A small command-line parser: positional arguments, `--flag`, `--key value` and repeated
/// keys (`--set a=1 --set b=2`). Unknown options are InputErrors naming the option.
#include "solvers/core/types.hpp"

#include <map>
#include <set>
#include <string>
#include <vector>

namespace cb {

class CommandLine {
public:
    /// @param value_options  options that take a value ("--out")
    /// @param flag_options   options without a value ("--json-only")
    CommandLine(const std::string& command, const std::vector<std::string>& args,
                const std::set<std::string>& value_options, const std::set<std::string>& flag_options);

    bool help() const { return m_help; }
    const std::vector<std::string>& positional() const { return m_positional; }
    bool has(const std::string& option) const { return m_values.count(option) != 0 || m_flags.count(option) != 0; }
    /// Last value of an option, or `fallback`.
    std::string value(const std::string& option, const std::string& fallback = "") const;
    /// Last value of an option that names a file or folder, or `fallback`; an empty value given
    /// on the command line (`--json ""`) is an InputError naming the option.
    std::string path(const std::string& option, const std::string& fallback = "") const;
    /// Every value of a repeated option, in order.
    std::vector<std::string> values(const std::string& option) const;
    double number(const std::string& option, double fallback) const;
    long integer(const std::string& option, long fallback) const;
    /// Throws InputError unless there are between min and max positional arguments.
    void expect_positional(size_t min, size_t max, const std::string& usage) const;

private:
    std::string m_command;
    std::vector<std::string> m_positional;
    std::map<std::string, std::vector<std::string>> m_values;
    std::set<std::string> m_flags;
    bool m_help = false;
};

}  // namespace cb
