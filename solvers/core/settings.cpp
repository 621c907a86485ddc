#include "solvers/core/settings.hpp"

#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>

namespace cb {

const SettingsTable<CommonSettings>& common_settings_table()
{
    using C = CommonSettings;
    static const SettingsTable<C> table =
        SettingsTable<C>()
            .number("tol", &C::tol, 0.0, 1e300,
                    "stop tolerance on the accuracy error e, dimensionless: residual lengths as a fraction of the "
                    "scene size (stop=kkt); or on the native residual in the paper's units (stop=native)")
            .row(
                "stop", [](const C& s) { return std::string(to_string(s.stop)); },
                "kkt | native: which criterion ends the solve (kkt = the accuracy error e of docs/accuracy.md)",
                [](SettingsReader& reader, C& s) {
                    s.stop = reader.choice("stop", to_string(s.stop), {"kkt", "native"}) == "kkt" ? StopRule::ACCURACY
                                                                                                  : StopRule::NATIVE;
                },
                [](const C& s, nlohmann::json& j) { j["stop"] = to_string(s.stop); }, {"kkt", "native"})
            .integer("max_iterations", &C::max_iterations, 0, MAX_ITERATIONS_LIMIT,
                     "cap on outer iterations (at most 10^12; bound long runs with time_limit_s)")
            .number("time_limit_s", &C::time_limit_s, -1e-300, 1e300,
                    "wall-time limit of the solve in seconds; 0 = none")
            .row(
                "seed", [](const C& s) { return std::to_string(s.seed); }, "seed of every random choice",
                [](SettingsReader& reader, C& s) {
                    s.seed = static_cast<std::uint64_t>(reader.integer("seed", static_cast<long>(s.seed), 0));
                },
                [](const C& s, nlohmann::json& j) { j["seed"] = s.seed; })
            .integer("threads", &C::threads, 1, MAX_THREADS,
                     "threads of the products with A, over fixed row ranges (same settings, same iterates; "
                     "threads > 1 may differ from 1 in the dots' last bits): docs/a_product.md")
            .row(
                "a_format", [](const C& s) { return std::string(to_string(s.a_format)); },
                "auto | csr | bsr | sbsr: storage of A for the solvers' products with A (bsr: 3x3 blocks, "
                "iterates bit-equal to csr's; sbsr: the upper block triangle, about half the bytes, iterates equal "
                "to rounding, one thread; auto: sbsr for an A of 1M nonzeros (2^20) or more on one thread, else bsr; a "
                "format A lacks falls back to csr, auto's sbsr to bsr first): docs/a_product.md",
                [](SettingsReader& reader, C& s) {
                    parse_a_format(reader.choice("a_format", to_string(s.a_format), {"auto", "csr", "bsr", "sbsr"}),
                                   s.a_format);
                },
                [](const C& s, nlohmann::json& j) { j["a_format"] = to_string(s.a_format); },
                {"auto", "csr", "bsr", "sbsr"});
    return table;
}

nlohmann::json CommonSettings::to_json() const
{
    nlohmann::json j = nlohmann::json::object();
    common_settings_table().write(*this, j);
    return j;
}

SettingsReader::SettingsReader(const nlohmann::json& settings, std::string where)
    : m_settings(settings.is_null() ? nlohmann::json::object() : settings), m_where(std::move(where))
{
    if (!m_settings.is_object()) throw_input_error(m_where, "", "settings must be a JSON object");
}

void SettingsReader::fail(const std::string& key, const std::string& problem) const
{
    throw_input_error(m_where, "/" + key, problem);
}

const nlohmann::json* SettingsReader::find(const std::string& key)
{
    m_read.insert(key);
    const auto it = m_settings.find(key);
    return it == m_settings.end() ? nullptr : &*it;
}

double SettingsReader::number(const std::string& key, double fallback, double min_exclusive, double max_inclusive)
{
    const nlohmann::json* value = find(key);
    if (!value) return fallback;
    if (!value->is_number()) fail(key, "expected a number, got " + value->dump());
    const double v = value->get<double>();
    if (!std::isfinite(v)) fail(key, "must be finite");
    if (!(v > min_exclusive)) {
        std::ostringstream s;
        s << "must be > " << min_exclusive << ", got " << v;
        fail(key, s.str());
    }
    if (!(v <= max_inclusive)) {
        std::ostringstream s;
        s << "must be <= " << max_inclusive << ", got " << v;
        fail(key, s.str());
    }
    return v;
}

long SettingsReader::integer(const std::string& key, long fallback, long min_inclusive, long max_inclusive)
{
    const nlohmann::json* value = find(key);
    if (!value) return fallback;
    // Compared as integers, never through a double: 9223372036854775807 as a double rounds up to
    // 2^63, which no long holds (the cast wrapped to a negative cap).
    long v = 0;
    bool above = false, below = false;
    if (value->is_number_unsigned()) {
        const std::uint64_t u = value->get<std::uint64_t>();
        above = u > static_cast<std::uint64_t>(LONG_MAX);
        if (!above) v = static_cast<long>(u);
    } else if (value->is_number_integer()) {
        v = static_cast<long>(value->get<std::int64_t>());
    } else if (value->is_number_float() && std::floor(value->get<double>()) == value->get<double>()) {
        const double d = value->get<double>();
        above = d >= 9223372036854775808.0;  // 2^63
        below = d < -9223372036854775808.0;
        if (!above && !below) v = static_cast<long>(d);
    } else {
        fail(key, "expected an integer, got " + value->dump());
    }
    if (below || (!above && v < min_inclusive))
        fail(key, "must be >= " + std::to_string(min_inclusive) + ", got " + value->dump());
    if (above || v > max_inclusive) fail(key, "must be <= " + std::to_string(max_inclusive) + ", got " + value->dump());
    return v;
}

bool SettingsReader::boolean(const std::string& key, bool fallback)
{
    const nlohmann::json* value = find(key);
    if (!value) return fallback;
    if (!value->is_boolean()) fail(key, "expected true or false, got " + value->dump());
    return value->get<bool>();
}

std::string SettingsReader::choice(const std::string& key, const std::string& fallback,
                                   const std::vector<std::string>& allowed)
{
    const nlohmann::json* value = find(key);
    if (!value) return fallback;
    std::string known;
    for (const auto& a : allowed) known += (known.empty() ? "" : " | ") + a;
    if (!value->is_string()) fail(key, "expected one of " + known + ", got " + value->dump());
    std::string v = value->get<std::string>();  // not const: returned by move
    for (const auto& a : allowed)
        if (a == v) return v;
    fail(key, "expected one of " + known + ", got \"" + v + "\"");
}

CommonSettings SettingsReader::common(CommonSettings defaults)
{
    common_settings_table().read(*this, defaults);  // each row falls back to the value it finds
    return defaults;
}

void SettingsReader::finish() const
{
    for (const auto& item : m_settings.items())
        if (!m_read.count(item.key())) {
            std::string known;
            for (const auto& k : m_read) known += (known.empty() ? "" : ", ") + k;
            fail(item.key(), "unknown setting; known: " + known);
        }
}

std::vector<SettingDoc> common_setting_docs() { return common_settings_table().docs(); }

std::vector<SettingDoc> common_default_overrides(const CommonSettings& defaults)
{
    const std::vector<SettingDoc> common = common_settings_table().docs();
    std::vector<SettingDoc> own = common_settings_table().docs(defaults), out;
    for (size_t i = 0; i < own.size(); ++i)
        if (own[i].default_value != common[i].default_value)
            out.push_back({own[i].key, own[i].default_value,
                           "(this solver's default; the common one is " + common[i].default_value + ")"});
    return out;
}

std::string setting_default_text(double value)
{
    char buffer[40];
    std::snprintf(buffer, sizeof(buffer), "%g", value);
    if (value != 0.0 && std::abs(value) < 1e-2) {  // 1e-3, not 0.001: the shortest exact e-form
        for (int digits = 0; digits <= 16; ++digits) {
            std::snprintf(buffer, sizeof(buffer), "%.*e", digits, value);
            if (std::strtod(buffer, nullptr) == value) break;
        }
    }
    std::string text = buffer;  // "1e-06" -> "1e-6", "1e+06" -> "1e6"
    const auto e = text.find('e');
    if (e != std::string::npos) {
        std::string mantissa = text.substr(0, e), exponent = text.substr(e + 1);
        const bool negative = !exponent.empty() && exponent[0] == '-';
        if (!exponent.empty() && (exponent[0] == '-' || exponent[0] == '+')) exponent.erase(0, 1);
        while (exponent.size() > 1 && exponent[0] == '0') exponent.erase(0, 1);
        text = mantissa + "e" + (negative ? "-" : "") + exponent;
    }
    return text;
}

}  // namespace cb
