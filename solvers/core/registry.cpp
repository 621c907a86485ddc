#include "solvers/core/registry.hpp"

#include <stdexcept>

namespace cb {

void SolverRegistry::add(const std::string& name, SolverEntry entry)
{
    if (!m_entries.emplace(name, std::move(entry)).second)
        throw std::logic_error("solver '" + name + "' registered twice");
}

const SolverEntry& SolverRegistry::entry(const std::string& name) const
{
    const auto it = m_entries.find(name);
    if (it == m_entries.end()) {
        std::string known;
        for (const auto& n : names()) known += (known.empty() ? "" : ", ") + n;
        throw InputError("solver '" + name + "' is not registered; known: " + known);
    }
    return it->second;
}

std::unique_ptr<Solver> SolverRegistry::create(const std::string& name, const nlohmann::json& settings) const
{
    return entry(name).make(settings);
}

std::vector<std::string> SolverRegistry::names() const
{
    std::vector<std::string> out;
    for (const auto& kv : m_entries) out.push_back(kv.first);
    return out;
}

namespace {

struct ExtraRegistrations {
    std::vector<void (*)(SolverRegistry&)> functions;
    bool registry_built = false;
};

ExtraRegistrations& extra_registrations()
{
    static ExtraRegistrations extra;
    return extra;
}

}  // namespace

void add_builtin_registration(void (*registration)(SolverRegistry&))
{
    ExtraRegistrations& extra = extra_registrations();
    if (extra.registry_built) throw std::logic_error("add_builtin_registration after the registry was built");
    for (auto* f : extra.functions)
        if (f == registration) throw std::logic_error("add_builtin_registration: the same registration twice");
    extra.functions.push_back(registration);
}

const SolverRegistry& builtin_registry()
{
    static const SolverRegistry registry = [] {
        SolverRegistry r;
        register_builtin_solvers(r);
        ExtraRegistrations& extra = extra_registrations();
        for (auto* f : extra.functions) f(r);
        extra.registry_built = true;
        return r;
    }();
    return registry;
}

}  // namespace cb
