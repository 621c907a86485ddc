// Settings declared once (solvers/core/settings.hpp SettingsTable): `--help`, the record (to_json)
// and the reader agree for every registered solver.
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/methods/template_solver.hpp"

#include <gtest/gtest.h>

#include <map>
#include <set>

namespace cb {
namespace {

std::string text_of(const nlohmann::json& value)
{
    if (value.is_string()) return value.get<std::string>();
    if (value.is_boolean()) return setting_default_text(value.get<bool>());
    if (value.is_number_integer()) return setting_default_text(value.get<long>());
    return setting_default_text(value.get<double>());
}

void expect_help_matches_record(const SolverRegistry& registry, const std::string& name)
{
    SCOPED_TRACE(name);
    const SolverEntry& entry = registry.entry(name);
    const nlohmann::json record = registry.create(name, nlohmann::json::object())->settings();
    std::vector<SettingDoc> docs = common_setting_docs();
    docs.insert(docs.end(), entry.settings.begin(), entry.settings.end());
    std::set<std::string> documented;
    for (const SettingDoc& d : docs) {
        documented.insert(d.key);
        ASSERT_TRUE(record.contains(d.key)) << d.key << " is documented but not recorded";
    }
    for (const auto& item : record.items()) EXPECT_TRUE(documented.count(item.key())) << item.key() << " undocumented";
    // The default printed by --help is the recorded default (a solver's row overrides the common one).
    std::map<std::string, std::string> shown;
    for (const SettingDoc& d : docs) shown[d.key] = d.default_value;
    for (const auto& [key, text] : shown) EXPECT_EQ(text, text_of(record[key])) << key;
    // Every recorded value reads back to the same record.
    EXPECT_EQ(registry.create(name, record)->settings(), record);
}

TEST(SettingsTable, HelpRecordAndReaderAgreeForEverySolver)
{
    for (const std::string& name : builtin_registry().names()) expect_help_matches_record(builtin_registry(), name);
    SolverRegistry own;
    own.add("template", template_entry());
    expect_help_matches_record(own, "template");
}

struct Toy {
    CommonSettings common;
    double step = 0.5;
    long rounds = 3;
    bool fast = false;
    std::string mode = "a";
};

const SettingsTable<Toy>& toy_table()
{
    static const SettingsTable<Toy> table =
        SettingsTable<Toy>()
            .choice("mode", &Toy::mode, {"a", "b"}, "a | b")
            .number("step", &Toy::step, 0.0, 1.0, "step", [](const Toy& t) { return t.mode == "b" ? 0.25 : t.step; })
            .integer("rounds", &Toy::rounds, 1, 10, "rounds")
            .boolean("fast", &Toy::fast, "fast");
    return table;
}

Toy read_toy(const nlohmann::json& settings)
{
    SettingsReader reader(settings, "toy");
    Toy t;
    t.common = reader.common();
    toy_table().read(reader, t);
    reader.finish();
    return t;
}

TEST(SettingsTable, ReadsChecksWritesAndDocuments)
{
    const Toy t = read_toy({{"step", 0.75}, {"rounds", 10}, {"fast", true}});
    EXPECT_DOUBLE_EQ(t.step, 0.75);
    EXPECT_EQ(t.rounds, 10);
    EXPECT_TRUE(t.fast);
    EXPECT_EQ(read_toy({{"mode", "b"}}).step, 0.25);  // a default that depends on a row above
    EXPECT_EQ(read_toy({{"mode", "b"}, {"step", 0.5}}).step, 0.5);
    nlohmann::json j;
    toy_table().write(t, j);
    EXPECT_EQ(j, nlohmann::json({{"mode", "a"}, {"step", 0.75}, {"rounds", 10}, {"fast", true}}));
    const std::vector<SettingDoc> docs = toy_table().docs();
    ASSERT_EQ(docs.size(), 4u);
    EXPECT_EQ(docs[1].key, "step");
    EXPECT_EQ(docs[1].default_value, "0.5");
    EXPECT_EQ(docs[3].default_value, "false");
    EXPECT_EQ(toy_table().choices("mode"), (std::vector<std::string>{"a", "b"}));
    // The reader's messages, unchanged by the table.
    EXPECT_THROW(
        {
            try {
                read_toy({{"step", 2.0}});
            } catch (const InputError& e) {
                EXPECT_STREQ(e.what(), "toy: /step: must be <= 1, got 2");
                throw;
            }
        },
        InputError);
    EXPECT_THROW(
        {
            try {
                read_toy({{"mode", "c"}});
            } catch (const InputError& e) {
                EXPECT_STREQ(e.what(), "toy: /mode: expected one of a | b, got \"c\"");
                throw;
            }
        },
        InputError);
    EXPECT_THROW(read_toy({{"rounds", 0}}), InputError);
    EXPECT_THROW(read_toy({{"other", 0}}), InputError);
}

/// A solver whose struct starts the common block from other defaults (as active-set's tol 1e-10).
struct StrictToy {
    CommonSettings common = CommonSettings{}.with_tol(1e-9);
    long rounds = 3;
};

class StrictToySolver final : public Solver {
public:
    explicit StrictToySolver(StrictToy settings) : m_settings(settings) {}
    std::string name() const override { return "strict-toy"; }
    nlohmann::json settings() const override { return nlohmann::json::object(); }
    SolverResult solve(const QpView&, const SolveContext&) override { return SolverResult{}; }
    StrictToy m_settings;
};

TEST(SettingsTable, SolverOwnCommonDefaultIsReadAndDocumented)
{
    static const SettingsTable<StrictToy> table =
        SettingsTable<StrictToy>().integer("rounds", &StrictToy::rounds, 1, 10, "rounds");
    EXPECT_EQ(read_settings(nlohmann::json::object(), "strict-toy", table).common.tol, 1e-9);
    EXPECT_EQ(read_settings({{"tol", 1e-4}}, "strict-toy", table).common.tol, 1e-4);
    // Only tol differs from the common block: one help line, before the solver's own rows.
    const SolverEntry entry = solver_entry<StrictToySolver>("strict-toy", table, "toy");
    ASSERT_EQ(entry.settings.size(), 2u);
    EXPECT_EQ(entry.settings[0].key, "tol");
    EXPECT_EQ(entry.settings[0].default_value, "1e-9");
    EXPECT_EQ(entry.settings[0].doc, "(this solver's default; the common one is 1e-6)");
    EXPECT_EQ(entry.settings[1].key, "rounds");
    EXPECT_TRUE(common_default_overrides(CommonSettings{}).empty());
    EXPECT_EQ(common_settings_table().docs(CommonSettings{}.with_tol(0.5))[0].default_value, "0.5");
}

TEST(SettingsTable, ActiveSetDefaultTolIsTheReferenceAccuracy)
{
    const SolverEntry& entry = builtin_registry().entry("active-set");
    ASSERT_FALSE(entry.settings.empty());
    EXPECT_EQ(entry.settings[0].key, "tol");
    EXPECT_EQ(entry.settings[0].default_value, "1e-10");
    EXPECT_EQ(builtin_registry().create("active-set", nlohmann::json::object())->settings()["tol"].get<double>(),
              1e-10);
}

TEST(SettingsTable, DefaultTexts)
{
    EXPECT_EQ(setting_default_text(1e-6), "1e-6");
    EXPECT_EQ(setting_default_text(1e-3), "1e-3");
    EXPECT_EQ(setting_default_text(1e-10), "1e-10");
    EXPECT_EQ(setting_default_text(0.1), "0.1");
    EXPECT_EQ(setting_default_text(1.0), "1");
    EXPECT_EQ(setting_default_text(0.0), "0");
    EXPECT_EQ(setting_default_text(2.5e-3), "2.5e-3");
}

}  // namespace
}  // namespace cb
