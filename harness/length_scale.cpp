#include "harness/length_scale.hpp"

#include "harness/reference.hpp"
#include "harness/suite.hpp"
#include "solvers/measure/accuracy.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace cb {

namespace {

/// |D^-1 (b - A x0)|_inf: one Jacobi step from the start. A nearly singular A cannot inflate it
/// (D is A's diagonal, not its smallest eigenvalue); it can only understate the solution's size.
double load_displacement(const Qp& qp)
{
    const Vec r = qp.b - qp.A * qp.x0;
    double widest = 0.0;
    for (Eigen::Index j = 0; j < qp.n(); ++j) {
        const double d = qp.A.coeff(j, j);
        if (d > 0.0 && std::isfinite(d)) widest = std::max(widest, std::abs(r[j]) / d);
    }
    return std::isfinite(widest) ? widest : 0.0;
}

template <class M> void append_matrix(std::string& bytes, const M& a)
{
    const SpMat s = a;  // compressed
    bytes.append(reinterpret_cast<const char*>(s.outerIndexPtr()), sizeof(*s.outerIndexPtr()) * (s.outerSize() + 1));
    bytes.append(reinterpret_cast<const char*>(s.innerIndexPtr()), sizeof(*s.innerIndexPtr()) * s.nonZeros());
    bytes.append(reinterpret_cast<const char*>(s.valuePtr()), sizeof(double) * s.nonZeros());
}

void append_vector(std::string& bytes, const Vec& v)
{
    bytes.append(reinterpret_cast<const char*>(v.data()), sizeof(double) * v.size());
}

}  // namespace

std::string qp_content_key(const Qp& qp)
{
    std::string bytes = std::to_string(qp.n()) + " " + std::to_string(qp.m()) + " " + qp.meta.dump() + "\n";
    append_matrix(bytes, qp.A);
    append_vector(bytes, qp.b);
    append_matrix(bytes, qp.J);
    append_vector(bytes, qp.c);
    append_vector(bytes, qp.x0);
    return "qp-" + fnv1a_hex(bytes);
}

double parse_length_scale(const std::string& where, const std::string& text)
{
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v) || !(v > 0.0))
        throw_input_error(where, "--length-scale", "expected a finite number > 0, got '" + text + "'");
    return v;
}

void fix_length_scale(Qp& qp, const std::string& where, const std::string& key, const GivenLength& given,
                      const std::string& cache)
{
    if (given.value > 0.0) {
        qp.length = {given.value, given.source};
        return;
    }
    if (qp.meta.is_object() && qp.meta.contains("length_scale")) {
        const nlohmann::json& v = qp.meta["length_scale"];
        if (!v.is_number() || !std::isfinite(v.get<double>()) || !(v.get<double>() > 0.0))
            throw_input_error(where, "meta.length_scale", "expected a finite number > 0, got " + v.dump());
        qp.length = {v.get<double>(), "snapshot"};
        return;
    }
    std::string unused;
    const double start = point_extent(qp.x0, unused);
    if (start > 0.0 && std::isfinite(start)) return;  // geometry: x0's extent, nothing to compute

    // No geometry: the size of the problem's own solution. The reference solve needs a scale for
    // its stop test; the load displacement can only understate l, which makes that test stricter.
    qp.length = {load_displacement(qp), "load_displacement"};
    const nlohmann::json ref = reference_solution(qp, key, cache);
    const nlohmann::json extent = ref.value("solution_extent", nlohmann::json());
    if (ref.value("objective", nlohmann::json()).is_number() && extent.is_number() && extent.get<double>() > 0.0 &&
        std::isfinite(extent.get<double>()))
        qp.length = {extent.get<double>(), "reference_extent"};
}

}  // namespace cb
