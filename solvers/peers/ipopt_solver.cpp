// Ipopt as an external peer (see ipopt_solver.hpp for the mapping of settings onto Ipopt's options).
#include "solvers/peers/ipopt_solver.hpp"
#include "solvers/core/solve_loop.hpp"

#include <IpIpoptApplication.hpp>
#include <IpIpoptCalculatedQuantities.hpp>
#include <IpIpoptData.hpp>
#include <IpOrigIpoptNLP.hpp>
#include <IpTNLP.hpp>
#include <IpTNLPAdapter.hpp>
#include <IpoptConfig.h>

#include <cmath>
#include <limits>
#include <sstream>

namespace cb {

namespace {

/// Its own settings, declared once (settings.hpp SettingsTable); the common block comes first.
const SettingsTable<IpoptSettings>& ipopt_settings_table()
{
    static const SettingsTable<IpoptSettings> table =
        SettingsTable<IpoptSettings>()
            .choice("nlp_scaling", &IpoptSettings::nlp_scaling, {"gradient-based", "none"},
                    "Ipopt's nlp_scaling_method: gradient-based or none")
            .integer("print_level", &IpoptSettings::print_level, 0, 12, "Ipopt's print_level (0 silent .. 12)");
    return table;
}

}  // namespace

IpoptSettings IpoptSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "ipopt", ipopt_settings_table());
}

nlohmann::json IpoptSettings::to_json() const { return write_settings(*this, ipopt_settings_table()); }

std::string ipopt_version() { return IPOPT_VERSION; }

namespace {

using Ipopt::Index;
using Ipopt::Number;

/// The QP as an Ipopt TNLP. Ipopt's Lagrangian is f + y'g, so for Jx >= c its multipliers are
/// <= 0 and ours are lambda = -y.
class QpTnlp : public Ipopt::TNLP {
public:
    QpTnlp(const QpView& qp, const SolveContext& context, const IpoptSettings& settings, SolveLoop& loop,
           SolverResult& result)
        : m_qp(qp), m_context(context), m_settings(settings), m_loop(loop), m_result(result),
          m_scale(accuracy_scale(qp)), m_x(qp.x0), m_lambda(Vec::Zero(qp.m())),
          m_base_iterations(result.counters.iterations)
    {
        for (int i = 0; i < qp.A.outerSize(); ++i)
            for (SpMat::InnerIterator it(qp.A, i); it; ++it)
                if (it.col() <= i) ++m_hess_nnz;
    }

    bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& style) override
    {
        n = static_cast<Index>(m_qp.n());
        m = static_cast<Index>(m_qp.m());
        nnz_jac_g = static_cast<Index>(m_qp.J.nonZeros());
        nnz_h_lag = static_cast<Index>(m_hess_nnz);
        style = C_STYLE;
        return true;
    }
    bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override
    {
        for (Index i = 0; i < n; ++i) x_l[i] = -2e19, x_u[i] = 2e19;  // beyond nlp_*_bound_inf: free
        for (Index i = 0; i < m; ++i) g_l[i] = m_qp.c[i], g_u[i] = 2e19;
        return true;
    }
    bool get_starting_point(Index n, bool init_x, Number* x, bool, Number*, Number*, Index, bool, Number*) override
    {
        if (init_x)
            for (Index i = 0; i < n; ++i) x[i] = m_qp.x0[i];
        return true;
    }
    bool eval_f(Index n, const Number* x, bool, Number& obj) override
    {
        const Eigen::Map<const Vec> xv(x, n);
        obj = objective(m_qp, xv);
        ++m_result.counters.a_products;
        return true;
    }
    bool eval_grad_f(Index n, const Number* x, bool, Number* grad) override
    {
        const Eigen::Map<const Vec> xv(x, n);
        Eigen::Map<Vec>(grad, n) = m_qp.A * xv - m_qp.b;
        ++m_result.counters.a_products;
        return true;
    }
    bool eval_g(Index n, const Number* x, bool, Index m, Number* g) override
    {
        const Eigen::Map<const Vec> xv(x, n);
        Eigen::Map<Vec>(g, m) = m_qp.J * xv;
        return true;
    }
    bool eval_jac_g(Index, const Number*, bool, Index, Index, Index* rows, Index* cols, Number* values) override
    {
        Index k = 0;
        for (int i = 0; i < m_qp.J.outerSize(); ++i)
            for (SpMat::InnerIterator it(m_qp.J, i); it; ++it, ++k) {
                if (values)
                    values[k] = it.value();
                else
                    rows[k] = i, cols[k] = static_cast<Index>(it.col());
            }
        return true;
    }
    bool eval_h(Index, const Number*, bool, Number obj_factor, Index, const Number*, bool, Index, Index* rows,
                Index* cols, Number* values) override
    {
        Index k = 0;
        for (int i = 0; i < m_qp.A.outerSize(); ++i)
            for (SpMat::InnerIterator it(m_qp.A, i); it; ++it) {
                if (it.col() > i) continue;  // lower triangle
                if (values)
                    values[k] = obj_factor * it.value();
                else
                    rows[k] = i, cols[k] = static_cast<Index>(it.col());
                ++k;
            }
        return true;
    }
    void finalize_solution(Ipopt::SolverReturn, Index n, const Number* x, const Number*, const Number*, Index m,
                           const Number*, const Number* y, Number, const Ipopt::IpoptData*,
                           Ipopt::IpoptCalculatedQuantities*) override
    {
        if (m_stopped_at_kkt || m_stopped_by_monitor) return;  // keep the point the callback judged
        m_x = Eigen::Map<const Vec>(x, n);
        m_lambda = -Eigen::Map<const Vec>(y, m);
    }

    bool intermediate_callback(Ipopt::AlgorithmMode, Index iter, Number, Number, Number inf_du, Number, Number, Number,
                               Number, Number, Index, const Ipopt::IpoptData* ip_data,
                               Ipopt::IpoptCalculatedQuantities* ip_cq) override
    {
        m_result.counters.iterations = m_base_iterations + iter;  // summed over re-solves
        current_iterate(ip_data, ip_cq);
        const Vec g = m_qp.A * m_x - m_qp.b;
        ++m_result.counters.a_products;
        // The loop's rule on this iterate; under stop=native Ipopt's own test ends the solve (+inf here).
        const bool kkt_ok = m_loop.criterion_met(std::numeric_limits<double>::infinity(), [&] {
            return accuracy_from_gradient(m_qp, m_scale, m_x, g, m_lambda).max();
        });
        m_native = inf_du;
        const StepKind step = iter == 0 ? StepKind::START : StepKind::OUTER;
        if (!m_loop.notify({iter, step, &m_x, &m_lambda, inf_du, -1, &m_result.counters, 0.0})) {
            m_stopped_by_monitor = true;
            return false;
        }
        if (kkt_ok) {
            m_stopped_at_kkt = true;
            return false;
        }
        if (m_loop.time_up()) {  // setup + solve, as every solver
            m_time_up = true;
            return false;
        }
        return true;
    }

    const Vec& x() const { return m_x; }
    const Vec& lambda() const { return m_lambda; }
    bool stopped_at_kkt() const { return m_stopped_at_kkt; }
    bool stopped_by_monitor() const { return m_stopped_by_monitor; }
    bool time_up() const { return m_time_up; }
    double native() const { return m_native; }

private:
    /// Ipopt's current iterate in the user's space: x, and the constraint multipliers unscaled
    /// the way Ipopt's own finalisation does it (d-scaling applied, objective scaling removed).
    void current_iterate(const Ipopt::IpoptData* ip_data, Ipopt::IpoptCalculatedQuantities* ip_cq)
    {
        auto* orig = dynamic_cast<Ipopt::OrigIpoptNLP*>(Ipopt::GetRawPtr(ip_cq->GetIpoptNLP()));
        if (!orig) return;
        auto* adapter = dynamic_cast<Ipopt::TNLPAdapter*>(Ipopt::GetRawPtr(orig->nlp()));
        if (!adapter) return;
        adapter->ResortX(*ip_data->curr()->x(), m_x.data());
        Ipopt::SmartPtr<Ipopt::Vector> y_d =
            orig->NLP_scaling()->apply_vector_scaling_d_NonConst(ip_data->curr()->y_d());
        y_d->Scal(orig->NLP_scaling()->unapply_obj_scaling(1.0));
        adapter->ResortG(*ip_data->curr()->y_c(), *y_d, m_lambda.data());
        m_lambda = -m_lambda;
    }

    const QpView& m_qp;
    const SolveContext& m_context;
    const IpoptSettings& m_settings;
    SolveLoop& m_loop;
    SolverResult& m_result;
    AccuracyScale m_scale;
    Vec m_x, m_lambda;
    long m_base_iterations = 0;
    long m_hess_nnz = 0;
    double m_native = 0.0;
    bool m_stopped_at_kkt = false, m_stopped_by_monitor = false, m_time_up = false;
};

const char* ipopt_status_name(Ipopt::ApplicationReturnStatus s)
{
    switch (s) {
    case Ipopt::Solve_Succeeded:
        return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level:
        return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected:
        return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small:
        return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates:
        return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop:
        return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found:
        return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded:
        return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed:
        return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation:
        return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded:
        return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom:
        return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition:
        return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option:
        return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected:
        return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception:
        return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown:
        return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory:
        return "Insufficient_Memory";
    case Ipopt::Internal_Error:
        return "Internal_Error";
    }
    return "unknown";
}

}  // namespace

SolverResult IpoptSolver::solve(const QpView& qp, const SolveContext& context)
{
    const IpoptSettings& s = m_settings;
    SolverResult result;
    result.x = qp.x0;
    result.lambda = Vec::Zero(qp.m());
    const double ipopt_tol = s.common.stops_on_native() ? s.common.tol : 1e-2 * s.common.tol;
    result.info["library"] = std::string("Ipopt ") + IPOPT_VERSION;
    result.info["native_residual_definition"] = "Ipopt's inf_du (scaled dual infeasibility) at its last iterate";
    result.info["ipopt_options"] = {{"tol", ipopt_tol},
                                    {"max_iter", s.common.max_iterations},
                                    {"max_cpu_time", s.common.time_limit_s > 0 ? s.common.time_limit_s : 1e6},
                                    {"bound_relax_factor", 0.0},
                                    {"hessian_constant", "yes"},
                                    {"jac_d_constant", "yes"},
                                    {"nlp_scaling_method", s.nlp_scaling},
                                    {"print_level", s.print_level}};
    result.info["history"] = "from Ipopt's intermediate callback (one entry per Ipopt iteration)";

    SolveLoop loop("ipopt", qp, s.common, context);
    Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
    app->Options()->SetNumericValue("tol", ipopt_tol);
    app->Options()->SetIntegerValue("max_iter", static_cast<Index>(std::min<long>(s.common.max_iterations, 1L << 30)));
    app->Options()->SetNumericValue("max_cpu_time", s.common.time_limit_s > 0 ? s.common.time_limit_s : 1e6);
    app->Options()->SetNumericValue("bound_relax_factor", 0.0);
    app->Options()->SetStringValue("hessian_constant", "yes");
    app->Options()->SetStringValue("jac_d_constant", "yes");
    app->Options()->SetStringValue("nlp_scaling_method", s.nlp_scaling);
    app->Options()->SetIntegerValue("print_level", static_cast<Index>(s.print_level));
    app->Options()->SetStringValue("sb", "yes");  // no banner
    if (app->Initialize() != Ipopt::Solve_Succeeded) {
        return loop.finish(result, SolveStatus::INVALID_INPUT, "ipopt: Ipopt rejected its options");
    }
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT);

    Ipopt::SmartPtr<QpTnlp> tnlp = new QpTnlp(qp, context, s, loop, result);
    Ipopt::ApplicationReturnStatus rc = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(Ipopt::GetRawPtr(tnlp)));
    // Ipopt's tolerance is on its own scaled error: it can declare success at a point where the
    // loop's rule does not hold. Then ask it for more (Ipopt tol / 1e3, down to 1e-14), at most
    // twice. The rule is the loop's: under stop=native it is Ipopt's own test, which its success
    // meets (no re-solve); under stop=kkt the accuracy error at the returned point.
    double tol_used = ipopt_tol;
    int retries = 0;
    const auto solved = [](Ipopt::ApplicationReturnStatus status) {
        return status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
    };
    const auto rule_holds_at_return = [&]() {
        return loop.rule_holds(solved(rc), [&] {
            const Vec g = qp.A * tnlp->x() - qp.b;
            ++result.counters.a_products;
            return tnlp->x().allFinite() && tnlp->lambda().allFinite()
                       ? accuracy_from_gradient(qp, accuracy_scale(qp), tnlp->x(), g, tnlp->lambda()).max()
                       : std::numeric_limits<double>::infinity();
        });
    };
    while (retries < 2 && tol_used > 1e-14 && solved(rc) && !rule_holds_at_return()) {
        ++retries;
        tol_used = std::max(1e-14, tol_used * 1e-3);
        app->Options()->SetNumericValue("tol", tol_used);
        tnlp = new QpTnlp(qp, context, s, loop, result);
        rc = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(Ipopt::GetRawPtr(tnlp)));
    }
    result.info["ipopt_retries"] = retries;
    result.info["ipopt_tol_last"] = tol_used;

    result.x = tnlp->x();
    result.lambda = tnlp->lambda();
    result.native_residual = tnlp->native();
    result.iterations = result.counters.iterations;
    result.info["ipopt_status"] = ipopt_status_name(rc);
    std::ostringstream msg;
    msg << "Ipopt " << IPOPT_VERSION << " returned " << ipopt_status_name(rc) << " after " << result.iterations
        << " iterations";
    if (retries > 0) msg << " (" << retries << " re-solve(s) with a tighter Ipopt tol, last " << tol_used << ")";

    // The verdict is the loop's rule at the returned point (stop=kkt: the accuracy error; stop=native:
    // Ipopt's own test with tol), never Ipopt's flag alone; Ipopt's return code names the rest.
    const Vec g = qp.A * result.x - qp.b;
    ++result.counters.a_products;
    // Ipopt's Invalid_Number_Detected is a NaN or Inf met in the problem's functions: not finite either.
    const bool finite = result.x.allFinite() && result.lambda.allFinite() && rc != Ipopt::Invalid_Number_Detected;
    const bool ipopt_solved = solved(rc);
    SolveStatus otherwise = SolveStatus::STALLED;  // Ipopt finished, the rule does not hold
    if (rc == Ipopt::Diverging_Iterates)
        otherwise = SolveStatus::DIVERGED;
    else if (rc == Ipopt::Infeasible_Problem_Detected)
        otherwise = SolveStatus::INFEASIBLE;
    else if (tnlp->time_up() || rc == Ipopt::Maximum_CpuTime_Exceeded)
        otherwise = SolveStatus::TIME_LIMIT;
    else if (rc == Ipopt::Maximum_Iterations_Exceeded)
        otherwise = SolveStatus::MAX_ITERATIONS;
    else if (rc == Ipopt::Invalid_Problem_Definition || rc == Ipopt::Not_Enough_Degrees_Of_Freedom)
        otherwise = SolveStatus::INVALID_INPUT;
    const SolveStatus status =
        tnlp->stopped_by_monitor()
            ? SolveStatus::STOPPED_BY_MONITOR
            : loop.verdict(
                  finite, ipopt_solved,
                  [&] { return accuracy_from_gradient(qp, accuracy_scale(qp), result.x, g, result.lambda).max(); },
                  otherwise);
    if (status == SolveStatus::CONVERGED && tnlp->stopped_at_kkt()) msg << " (stopped by the harness's test)";
    return loop.finish(result, status, !loop.owns(status) ? "ipopt: " + msg.str() : msg.str());
}

SolverEntry ipopt_entry()
{
    SolverEntry e =
        solver_entry<IpoptSolver>("ipopt", ipopt_settings_table(),
                                  std::string("peer: Ipopt ") + IPOPT_VERSION +
                                      " interior point (MUMPS) on the primal QP, any J, bound_relax_factor 0",
                                  "any J (interior point on the primal QP)");
    e.library = std::string("Ipopt ") + IPOPT_VERSION;
    return e;
}

}  // namespace cb
