// Metamorphic tests of the accuracy measure (docs/accuracy.md) on a simulator snapshot (the
// stress suite's FEM scene) and synthetic families: the four maps of the issue
//   (a) A, b -> a A, a b              (lambda -> a lambda)
//   (b) J_i, c_i -> s_i J_i, s_i c_i  (lambda_i -> lambda_i / s_i)
//   (c) a rigid translation t: x0 -> x0 + t, b -> b + A t, c -> c + J t   (x -> x + t)
//   (d) a change of length unit k: x -> k x, A -> A / k^2, b -> b / k, c -> k c (lambda -> lambda / k)
// leave the measure of mapped points unchanged (power-of-two factors: to 1e-9 relative; the
// translation, where g = Ax - b cancels, to tol / 10), and every solver's "converged" holds on
// the mapped problem with the status it has on the original (known exceptions listed). Solvers
// whose iteration counts change under a map are reported, not failed.
// Plus the done-when checks: mprgp on coupled rows, infeasible sets, a start moved by 1 km.
#include "harness/runner.hpp"
#include "harness/stress_families.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"

#include <gtest/gtest.h>
#include <cmath>
#include <functional>
#include <iostream>
#include <map>
#include <string>
#include <vector>

namespace cb {
namespace {

constexpr double METAMORPHIC_TOL = 1e-6;

/// A named problem and a point (x, lambda) near its solution, not on it (every part nonzero-ish).
struct MetamorphicFixture {
    std::string name;
    Qp qp;
};

const std::vector<MetamorphicFixture>& fixtures()
{
    static const std::vector<MetamorphicFixture> all = [] {
        std::vector<MetamorphicFixture> f;
        f.push_back({"plane", make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 3)});
        f.push_back({"coupled", make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5)});
        const auto fem = select_stress_cases(stress_cases(false), {"fem-stiff-1e10"});
        f.push_back({"fem-stiff-1e10 (simulator snapshot)", make_stress_qp(fem.at(0))});
        return f;
    }();
    return all;
}

/// A deterministic point near the solution: the reference solve perturbed by a smooth pattern.
std::pair<Vec, Vec> probe_point(const Qp& qp)
{
    RunOptions options;
    options.record_history = false;
    options.decouple = "none";
    const RunOutcome ref = run_solver(qp, "active-set", {{"tol", 1e-10}}, options);
    Vec x = ref.result.x, lambda = ref.lambda_full;
    const AccuracyScale s = accuracy_scale(qp.view());
    for (Eigen::Index j = 0; j < x.size(); ++j) x[j] += 1e-4 * s.length * std::sin(0.7 * static_cast<double>(j));
    for (Eigen::Index i = 0; i < lambda.size(); ++i) lambda[i] *= 1.0 + 0.25 * std::cos(1.3 * static_cast<double>(i));
    if (lambda.size() > 0) lambda[0] = -std::abs(lambda[0]) - 1.0;  // a dual violation too
    return {x, lambda};
}

struct MappedQp {
    std::string name;
    Qp qp;
    std::function<Vec(const Vec&)> map_x, map_lambda, unmap_x, unmap_lambda;
    bool exact = true;  ///< power-of-two map: agreement to 1e-9 relative; else to tol / 10
};

Qp scale_objective(const Qp& qp, double a)
{
    Qp out = qp;
    out.A *= a;
    out.b *= a;
    return out;
}

/// Row i scaled by 2^(k_i), k_i cycling through -20..20.
Vec row_factors(Eigen::Index m)
{
    Vec s(m);
    for (Eigen::Index i = 0; i < m; ++i) s[i] = std::ldexp(1.0, static_cast<int>((7 * i) % 41) - 20);
    return s;
}

Qp scale_rows(const Qp& qp, const Vec& s)
{
    Qp out = qp;
    out.J = s.asDiagonal() * qp.J;
    out.c = s.cwiseProduct(qp.c);
    return out;
}

Qp change_unit(const Qp& qp, double k)
{
    Qp out = qp;
    out.A /= k * k;
    out.b /= k;
    out.c *= k;
    out.x0 *= k;
    return out;
}

/// t: the same 3-vector on every vertex (a rigid move of the scene).
Vec rigid_shift(Eigen::Index n, double tx, double ty, double tz)
{
    Vec t(n);
    for (Eigen::Index j = 0; j < n; ++j) t[j] = (j % 3 == 0) ? tx : (j % 3 == 1 ? ty : tz);
    return t;
}

Qp translate(const Qp& qp, const Vec& t)
{
    Qp out = qp;
    out.x0 += t;
    out.b += qp.A * t;
    out.c += qp.J * t;
    return out;
}

std::vector<MappedQp> maps_of(const Qp& qp)
{
    std::vector<MappedQp> maps;
    const auto same = [](const Vec& v) { return v; };
    for (int e : {-26, 26}) {  // a = 2^-26 ~ 1.5e-8 and 2^26 ~ 6.7e7
        const double a = std::ldexp(1.0, e);
        maps.push_back({"(a) objective x 2^" + std::to_string(e), scale_objective(qp, a), same,
                        [a](const Vec& l) { return Vec(a * l); }, same, [a](const Vec& l) { return Vec(l / a); },
                        true});
    }
    const Vec s = row_factors(qp.m());
    maps.push_back({"(b) rows x 2^-20..2^20", scale_rows(qp, s), same,
                    [s](const Vec& l) { return Vec(l.cwiseQuotient(s)); }, same,
                    [s](const Vec& l) { return Vec(l.cwiseProduct(s)); }, true});
    for (int e : {-10, 10}) {  // k = 2^10 ~ 1e3: m -> mm; 2^-10: m -> km
        const double k = std::ldexp(1.0, e);
        maps.push_back({"(d) length unit x 2^" + std::to_string(e), change_unit(qp, k),
                        [k](const Vec& x) { return Vec(k * x); }, [k](const Vec& l) { return Vec(l / k); },
                        [k](const Vec& x) { return Vec(x / k); }, [k](const Vec& l) { return Vec(k * l); }, true});
    }
    const Vec t = rigid_shift(qp.n(), 1000.0, -700.0, 300.0);  // about 1.3 km
    maps.push_back({"(c) translation by 1.3 km", translate(qp, t), [t](const Vec& x) { return Vec(x + t); }, same,
                    [t](const Vec& x) { return Vec(x - t); }, same, false});
    return maps;
}

void expect_same_measure(const AccuracyParts& e, const AccuracyParts& f, bool exact, const std::string& what)
{
    const double parts_e[] = {e.stationarity, e.primal, e.dual, e.complementarity, e.gap, e.max()};
    const double parts_f[] = {f.stationarity, f.primal, f.dual, f.complementarity, f.gap, f.max()};
    const char* names[] = {"stationarity", "primal", "dual", "complementarity", "gap", "max"};
    for (int k = 0; k < 6; ++k) {
        const double bound = exact ? 1e-9 * std::abs(parts_e[k]) : METAMORPHIC_TOL / 10;
        EXPECT_NEAR(parts_f[k], parts_e[k], bound) << what << ": " << names[k];
    }
}

}  // namespace

TEST(AccuracyMetamorphic, MeasureOfMappedPointsAgrees)
{
    for (const MetamorphicFixture& fx : fixtures()) {
        const auto [x, lambda] = probe_point(fx.qp);
        const AccuracyScale scale = accuracy_scale(fx.qp.view());
        const AccuracyParts e = accuracy(fx.qp.view(), scale, x, lambda);
        // The probe is off the solution in every part, so the agreement is not 0 = 0.
        ASSERT_GT(e.stationarity, 1e-8) << fx.name;
        ASSERT_GT(e.dual, 1e-8) << fx.name;
        for (const MappedQp& mp : maps_of(fx.qp)) {
            const std::string what = fx.name + " " + mp.name;
            const AccuracyScale mapped_scale = accuracy_scale(mp.qp.view());
            EXPECT_EQ(mapped_scale.length_source, scale.length_source) << what;
            const AccuracyParts f = accuracy(mp.qp.view(), mapped_scale, mp.map_x(x), mp.map_lambda(lambda));
            expect_same_measure(e, f, mp.exact, what);
        }
    }
}

/// (solver, map) whose status changes under the map, with the status it has there: the known
/// findings about solvers (not failures of the measure). Any other change fails, and so does
/// one of these that goes away (update the list).
const std::map<std::pair<std::string, std::string>, std::string>& known_status_changes()
{
    static const std::map<std::pair<std::string, std::string>, std::string> known = {
        // Ipopt's own scaling stalls on an objective scaled by 2^-26 (both fixtures).
        {{"ipopt", "(a) objective x 2^-26"}, "stalled"},
        // The local-form entries stop on FCLIB's natural map, r - P_K(r - u~), which adds a reaction
        // to a velocity: scaling the objective scales r and not u, scaling rows scales both apart,
        // so a point at FCLIB error ~1e-9 can be far from e <= tol. Their rounds tighten the own
        // tolerance (docs/friction.md) and then stall honestly.
        {{"mprgp-tresca-fp", "(a) objective x 2^-26"}, "stalled"},
        {{"mprgp-tresca-fp", "(b) rows x 2^-20..2^20"}, "stalled"},
        {{"mprgp+ica-friction", "(b) rows x 2^-20..2^20"}, "stalled"},
    };
    return known;
}

// Every solver, on every mapped problem: its status is the one it has on the original problem
// (but the known findings above), a "converged" run holds to tol there, and mapped back to the
// original problem. Iteration counts that change under a map are printed (a finding about the
// solver, not a failure of the measure).
TEST(AccuracyMetamorphic, EverySolversConvergedHoldsOnTheMappedProblem)
{
    RunOptions options;
    options.record_history = false;
    const std::vector<std::string> solvers = builtin_registry().names();
    long converged_runs = 0;
    for (const MetamorphicFixture& fx : fixtures()) {
        if (fx.qp.n() > 700) continue;  // the FEM snapshot: measure only (a solver sweep there is slow)
        for (const std::string& solver : solvers) {
            const RunOutcome base = run_solver(fx.qp, solver, {{"tol", METAMORPHIC_TOL}}, options);
            for (const MappedQp& mp : maps_of(fx.qp)) {
                const std::string what = fx.name + " / " + solver + " / " + mp.name;
                const RunOutcome run = run_solver(mp.qp, solver, {{"tol", METAMORPHIC_TOL}}, options);
                if (run.result.iterations != base.result.iterations)
                    std::cout << "[ finding ] " << what << ": " << base.status << " in " << base.result.iterations
                              << " iterations -> " << run.status << " in " << run.result.iterations << "\n";
                // A known finding may show on one fixture and not on the other.
                const auto known = known_status_changes().find({solver, mp.name});
                const bool known_change = known != known_status_changes().end() && run.status == known->second;
                EXPECT_TRUE(run.status == base.status || known_change)
                    << what << ": " << base.status << " -> " << run.status << ": " << run.result.message;
                if (run.status != "converged") continue;
                ++converged_runs;
                // The run's point and multipliers mapped back: the measure agrees on the original
                // problem (to rounding; to tol / 10 for the translation), so it holds there too.
                const AccuracyParts own = accuracy(mp.qp.view(), run.result.x, run.lambda_full);
                const AccuracyParts back =
                    accuracy(fx.qp.view(), mp.unmap_x(run.result.x), mp.unmap_lambda(run.lambda_full));
                EXPECT_LE(own.max(), METAMORPHIC_TOL * (1 + 1e-9)) << what;
                expect_same_measure(own, back, mp.exact, what);
            }
        }
    }
    EXPECT_GT(converged_runs, 0);
}

// The case: mprgp on coupled vertex-triangle rows solves a decoupled QP. Its run is
// "converged" only when the ORIGINAL rows hold; otherwise solved_relaxation, with the reduced
// problem's numbers beside.
TEST(AccuracyMetamorphic, MprgpOnCoupledRowsIsConvergedOnlyWhenTheOriginalRowsHold)
{
    const Qp qp = make_synthetic("coupled", {}, 5);
    RunOptions options;
    options.record_history = false;
    const RunOutcome run = run_solver(qp, "mprgp", {{"tol", METAMORPHIC_TOL}}, options);
    ASSERT_EQ(run.result.status, SolveStatus::CONVERGED) << run.result.message;
    ASSERT_LT(run.m_solved, qp.m());
    EXPECT_LE(run.accuracy_solved.max(), METAMORPHIC_TOL * (1 + 1e-9));
    // Dropped rows are violated by far more than tol of the scene size at mprgp's point.
    EXPECT_GT(run.accuracy.primal, 100 * METAMORPHIC_TOL);
    EXPECT_EQ(run.status, "solved_relaxation");
    EXPECT_EQ(run.record["status"], "solved_relaxation");
    EXPECT_EQ(run.record["solver_status"], "converged");
    EXPECT_EQ(run.record["m_solved"].get<long>(), run.m_solved);
    EXPECT_TRUE(run.status_confirmed);  // its claim holds on the problem it solved
    // A solver on the original rows reaches converged on the same snapshot.
    const RunOutcome coupled = run_solver(qp, "mprgp-coupled", {{"tol", METAMORPHIC_TOL}}, options);
    EXPECT_EQ(coupled.status, "converged") << coupled.result.message;
    EXPECT_LE(coupled.accuracy.max(), METAMORPHIC_TOL * (1 + 1e-9));
}

// An empty feasible set: no solver's run is "converged", whatever it says.
TEST(AccuracyMetamorphic, InfeasibleSetIsNeverConverged)
{
    RunOptions options;
    options.record_history = false;
    for (const StressCase& c : select_stress_cases(stress_cases(false), {"infeasible"})) {
        const Qp qp = make_stress_qp(c);
        for (const std::string& solver : builtin_registry().names()) {
            // A cap keeps the solvers that iterate on an empty set (siconos-nsn: 10,000 Newton
            // steps, over a minute) short; the claim tested is the verdict, not the iteration count.
            const RunOutcome run =
                run_solver(qp, solver, {{"tol", METAMORPHIC_TOL}, {"max_iterations", 1000}}, options);
            EXPECT_NE(run.status, "converged") << c.id << " / " << solver << ": " << run.result.message;
            EXPECT_GT(run.accuracy.primal, METAMORPHIC_TOL) << c.id << " / " << solver;
        }
    }
}

// The same QP from a start moved rigidly by 1 km: same scene size, and every converged run
// reaches the same accuracy (e <= tol) and the same objective to within the energy bound.
TEST(AccuracyMetamorphic, StartMovedOneKilometreGivesTheSameConvergedAccuracy)
{
    const Qp qp = make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 3);
    Qp moved = qp;
    moved.x0 += rigid_shift(qp.n(), 1000.0, 0.0, 0.0);
    const double l = accuracy_scale(qp.view()).length;
    EXPECT_NEAR(accuracy_scale(moved.view()).length, l, 1e-12 * l);  // 1000 m added: rounding only
    RunOptions options;
    options.record_history = false;
    const RunOutcome ref = run_solver(qp, "active-set", {{"tol", 1e-10}}, options);
    ASSERT_EQ(ref.status, "converged");
    const AccuracyScale scale = accuracy_scale(qp.view());
    for (const std::string& solver : builtin_registry().names()) {
        for (const Qp* p : {&qp, static_cast<const Qp*>(&moved)}) {
            const RunOutcome run = run_solver(*p, solver, {{"tol", METAMORPHIC_TOL}}, options);
            if (run.status != "converged") continue;
            const std::string what = solver + (p == &qp ? " (start)" : " (start moved 1 km)");
            EXPECT_LE(run.accuracy.max(), METAMORPHIC_TOL * (1 + 1e-9)) << what;
            EXPECT_LE(energy_gap(scale, run.objective, ref.objective), 2 * METAMORPHIC_TOL) << what;
        }
    }
}

}  // namespace cb
